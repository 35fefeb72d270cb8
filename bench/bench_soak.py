"""Soak: an hour of video at 7 frames/s through `vistrack track`, memory sampled.

    python bench/bench_soak.py [--loops 125] [--write docs/benchmarks.md]

The bundled clip (200 frames of PETS09-S2L1, 7 frames/s) is written `--loops` times over into
one video (125 loops: 25,000 frames, an hour at 7 frames/s), which `vistrack track` then runs
through its whole chain (background model, blobs, box tracker, and every output: tracks, CSV,
annotated video, plot). The resident memory of the process (VmRSS, from /proc) is sampled
every half second; the growth is the last sample against the first one after 10 % of the
frames (the background model, the kernels and the writers are set up by then). The frames
end when ``tracks.txt`` appears: the results file is the first output closed, so its
appearance marks the start of closing the outputs (the trajectory plot is drawn then). The
growth over the frames is the median of the samples in the last tenth of the frames against
the median of those in the tenth after the first 10 % (single samples move by a few MB).
"""

from __future__ import annotations

import argparse
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2

ROOT = Path(__file__).resolve().parents[1]
CLIP = ROOT / "src" / "vistrack" / "data" / "pets09-s2l1" / "pets09-s2l1.mp4"
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _markdown import replace_section  # noqa: E402


def looped_video(path: Path, loops: int) -> tuple[int, float]:
    """Write the bundled clip ``loops`` times over into ``path``; (frames, frames per second)."""
    cap = cv2.VideoCapture(str(CLIP))
    fps = cap.get(cv2.CAP_PROP_FPS) or 7.0
    frames = []
    while True:
        ok, img = cap.read()
        if not ok:
            break
        frames.append(img)
    h, w = frames[0].shape[:2]
    out = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, (w, h))
    for _ in range(loops):
        for img in frames:
            out.write(img)
    out.release()
    return loops * len(frames), fps


def rss_mb(pid: int) -> float | None:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        return None
    return None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--loops", type=int, default=125, help="times the clip is repeated")
    ap.add_argument("--write", metavar="MD", help="write the section into this markdown file")
    args = ap.parse_args(argv)
    if not Path("/proc/self/status").exists():
        sys.exit("bench_soak reads memory from /proc: Linux only")

    with tempfile.TemporaryDirectory(prefix="vt-soak-") as tmp:
        video = Path(tmp) / "soak.mp4"
        n, fps = looped_video(video, args.loops)
        print(f"{n} frames at {fps:g} frames/s ({n / fps / 3600:.2f} h)", flush=True)
        out_dir = Path(tmp) / "out"
        cmd = [str(Path(sys.executable).parent / "vistrack"), "track", str(video), "--out-dir",
               str(out_dir), "--quiet"]
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        samples: list[tuple[float, float]] = []
        closing = None  # the first sample taken with tracks.txt there
        while proc.poll() is None:
            done = (out_dir / "tracks.txt").exists()
            r = rss_mb(proc.pid)
            if r is not None:
                if done and closing is None:
                    closing = len(samples)
                samples.append((time.perf_counter() - t0, r))
            time.sleep(0.5)
        out, err = proc.communicate()
        wall = time.perf_counter() - t0
        if proc.returncode:
            sys.exit(f"vistrack track failed ({proc.returncode}): {err[-2000:]}")
    # frames are processed at a near-constant rate: 10 % of the run is about 10 % of the frames
    settled = [r for t, r in samples if t >= 0.1 * wall]
    first, last, peak = settled[0], settled[-1], max(r for _, r in samples)
    growth = last - first
    # the frames' samples after the first 10 %: medians of their second and last tenths
    frames = [r for t, r in samples[:closing] if t >= 0.1 * wall] or settled
    tenth = max(1, len(frames) // 10)
    early, late = statistics.median(frames[:tenth]), statistics.median(frames[-tenth:])
    print(out.strip())
    print(f"RSS after 10 % of the run {first:.0f} MB, at the end {last:.0f} MB, peak {peak:.0f} "
          f"MB: growth {growth:+.1f} MB over {wall:.0f} s ({n / wall:.0f} frames/s whole "
          f"process); over the frames (medians of tenths) {early:.1f} MB to {late:.1f} MB: "
          f"{late - early:+.1f} MB")
    if args.write:
        replace_section(args.write, "\n".join([
            "## Soak",
            "",
            f"Measured with `python bench/bench_soak.py --loops {args.loops}` "
            f"({platform.python_implementation()} {platform.python_version()}): the bundled "
            f"clip looped into {n:,} frames ({n / fps / 3600:.2f} h at {fps:g} frames/s) "
            "through `vistrack track` with every output, the process's resident memory "
            "sampled every 0.5 s.",
            "",
            "| frames | wall s | RSS after 10 % MB | RSS at the end MB | peak MB | growth MB "
            "| growth over the frames MB |",
            "|---:|---:|---:|---:|---:|---:|---:|",
            f"| {n:,} | {wall:.0f} | {first:.0f} | {last:.0f} | {peak:.0f} | {growth:+.1f} "
            f"| {late - early:+.1f} |",
            "",
            "Goal: growth ≤ 20 MB over the run.",
            "",
        ]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
