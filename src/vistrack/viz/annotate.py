"""Draw tracks on frames: boxes, identities, trails and covariance ellipses (OpenCV)."""

from __future__ import annotations

import functools
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from ..types import Frame, Tracks

__all__ = ["Annotator", "AnnotatedVideo", "id_colour", "PALETTE_SIZE", "text_scale"]


PALETTE_SIZE = 64
"""Colours in :func:`id_colour`'s palette; identity ``i`` and ``i + 64`` share one."""


def _oklab_to_linear_rgb(lab: np.ndarray) -> np.ndarray:
    """OKLab ``(N, 3)`` to linear sRGB (B. Ottosson's matrices, 2020)."""
    L, a, b = lab.T
    lms = np.stack([L + 0.3963377774 * a + 0.2158037573 * b,
                    L - 0.1055613458 * a - 0.0638541728 * b,
                    L - 0.0894841775 * a - 1.2914855480 * b], axis=-1) ** 3
    return lms @ np.array([[4.0767416621, -1.2684380046, -0.0041960863],
                           [-3.3077115913, 2.6097574011, -0.7034186147],
                           [0.2309699292, -0.3413193965, 1.7076147010]])


@functools.cache
def _palette() -> tuple[tuple[int, int, int], ...]:
    """Bright colours each as far as can be from the ones before it: from a grid of OKLab
    colours inside sRGB (lightness 0.6 to 0.92, chroma at least 0.08), each next colour is
    the one farthest (Euclidean in OKLab, which is close to perceived difference) from all
    chosen so far, starting away from black and white."""
    L, a, b = np.meshgrid(np.linspace(0.6, 0.92, 9), np.linspace(-0.35, 0.35, 57),
                          np.linspace(-0.35, 0.35, 57), indexing="ij")
    lab = np.stack([L.ravel(), a.ravel(), b.ravel()], axis=1)
    lin = _oklab_to_linear_rgb(lab)
    lab = lab[((lin >= 0) & (lin <= 1)).all(axis=1) & (np.hypot(lab[:, 1], lab[:, 2]) >= 0.08)]
    d = np.minimum(np.linalg.norm(lab - [0.2, 0, 0], axis=1),
                   np.linalg.norm(lab - [1.0, 0, 0], axis=1))
    chosen = []
    for _ in range(PALETTE_SIZE):
        k = int(np.argmax(d))
        chosen.append(lab[k])
        d = np.minimum(d, np.linalg.norm(lab - lab[k], axis=1))
    lin = np.clip(_oklab_to_linear_rgb(np.array(chosen)), 0.0, 1.0)
    rgb = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055)
    return tuple((int(round(255 * b)), int(round(255 * g)), int(round(255 * r)))
                 for r, g, b in rgb)


def id_colour(i: int) -> tuple[int, int, int]:
    """A bright BGR colour for identity ``i``, far from every other identity's among the
    nearest 64 (a palette chosen farthest-first in OKLab: among identities 1 to 30 no two
    colours are closer than 10 CIEDE2000 units; golden-ratio hues, before, put two within 1).

    Parameters
    ----------
    i : int
        The identity.

    Returns
    -------
    tuple of int
        ``(blue, green, red)``, each 0 to 255.

    Examples
    --------
    >>> id_colour(1) != id_colour(2), id_colour(1) == id_colour(1 + PALETTE_SIZE)
    (True, True)
    """
    return _palette()[(int(i) - 1) % PALETTE_SIZE]


LABEL_COVER = 0.1
"""The share of a frame that :class:`Annotator`'s identity numbers may cover (each number's
box with its outline) for them to be drawn, by default."""


def text_scale(shape: tuple[int, ...]) -> float:
    """How much larger than at 720 pixels :class:`Annotator` draws its text and lines on an
    image of ``shape`` (``(H, W, ...)``): they grow with images larger than 720 pixels on
    their short side, so that they read on a 4K frame as on a PAL one.

    >>> text_scale((576, 768, 3)), text_scale((1080, 1920, 3)), text_scale((2160, 3840))
    (1.0, 1.5, 3.0)
    """
    return max(1.0, min(shape[:2]) / 720)


class Annotator:
    """Draws one frame's tracks, remembering each identity's recent centres for its trail.

    Parameters
    ----------
    trail : int
        Frames of trail kept per identity, drawn while the identity is in the frame; an
        identity unseen for that long is forgotten (memory stays bounded on long videos).
    nsigma : float
        Size of the covariance ellipse of a track's centre, in standard deviations.
    labels : bool, optional
        Draw each track's identity beside it. Default: while the frame's numbers would
        cover at most a tenth of the image (``LABEL_COVER``), and, once left out, again
        only where they would cover a twentieth or less, so that they do not come and go
        from frame to frame near the line; among hundreds of particles in a microscope's
        frame they hid the image.

    Examples
    --------
    >>> from vistrack.types import Tracks
    >>> ann = Annotator()
    >>> tracks = Tracks(ids=np.array([3]), boxes=np.array([[10, 10, 30, 40.0]]), points=None,
    ...                 scores=np.ones(1), classes=np.zeros(1))
    >>> out = ann.draw(np.zeros((60, 80, 3), np.uint8), tracks, label="frame 1")
    >>> tuple(out[25, 10]) == id_colour(3)   # the box's left side
    True
    """

    def __init__(self, trail: int = 30, nsigma: float = 2.0, labels: bool | None = None):
        self.trail, self.nsigma = int(trail), float(nsigma)
        if self.trail < 0:
            raise ValueError(f"trail must be a number of frames >= 0; got {trail}")
        self.labels = labels
        self._numbered = True  # (labels None) the numbers drawn in the last frame
        # each identity's recent centres, in whole pixels, in a slot of one array: a ring
        # of C centres, the c-th at c % C and again at c % C + C, so that its last C
        # centres, oldest first, are one contiguous slice (read without a copy). C grows,
        # doubling, as the centres held do, up to the trail, so that memory follows the
        # trails drawn rather than the trail asked for. ``_slot`` holds the identities in the
        # order first seen, the order their trails are drawn in
        self._slot: dict[int, int] = {}
        self._last: dict[int, int] = {}
        self._laid = self.trail  # the trail the slots are laid out for (trail may be changed)
        self._C = min(self.trail, 32)
        self._buf = np.zeros((0, 2 * self._C, 2), np.int32)
        self._count = np.zeros(0, np.int64)
        self._free: list[int] = []
        self._n = 0
        # each number's text size at a scale and thickness, measured once (OpenCV's call for
        # every number of every frame was a tenth of a frame of 520 particles)
        self._sizes: dict[tuple[int, float, int], Any] = {}

    def draw(self, image: np.ndarray, tracks: Tracks, label: str | None = None) -> np.ndarray:
        """A copy of the BGR ``image`` with ``tracks`` (:class:`vistrack.tracking.Tracks`)
        drawn.

        Each identity in its colour (:func:`id_colour`): its trail of recent centres, the
        ``nsigma`` ellipse of its centre's covariance (where the tracks have ``covs``), its
        box (or a dot at its point) and its number (as ``labels`` says); ``label`` at the
        top left. Each call is one frame of the trails.

        Parameters
        ----------
        image : (H, W, 3) or (H, W) uint8 ndarray
            The frame, BGR or grey (drawn on in colour); not changed.
        tracks : Tracks
            The frame's tracks, boxes or points.
        label : str, optional
            A caption, such as the frame's number.

        Returns
        -------
        (H, W, 3) uint8 ndarray
            The drawing.

        Examples
        --------
        Point tracks on a grey frame:

        >>> from vistrack.types import Tracks
        >>> tracks = Tracks(ids=np.array([1]), boxes=None, points=np.array([[40.0, 30.0]]),
        ...                 scores=np.ones(1), classes=np.zeros(1))
        >>> out = Annotator().draw(np.zeros((60, 80), np.uint8), tracks)
        >>> out.shape, tuple(out[30, 40]) == id_colour(1)
        ((60, 80, 3), True)
        """
        import cv2

        out = image.copy() if image.ndim == 3 else cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
        z = text_scale(out.shape)  # (sizes below are at scale 1)
        thin, thick = max(1, round(z)), max(2, round(2 * z))
        H, W = out.shape[:2]
        banner = (0, 0)  # the label's box: right and bottom edges
        if label:
            # white on a black box: an outlined label read double ("frame 101" as "1011") on
            # a light background once the video was compressed. The box is drawn first, so
            # that the tracks go over it and it hides none; the text last, on a black halo,
            # so that no track hides it ("frame 26" read "frame 2o" under a crowd's trails)
            label_scale = 0.6 * z
            (w, h), base = cv2.getTextSize(label, cv2.FONT_HERSHEY_SIMPLEX, label_scale, thin)
            if round(12 * z) + w > W:
                # narrower than the label: smaller text, whole ("frame 100" on a frame 80
                # wide was cut to "frame 10")
                label_scale *= max(W - round(12 * z), 1) / w
                (w, h), base = cv2.getTextSize(label, cv2.FONT_HERSHEY_SIMPLEX, label_scale,
                                               thin)
            at_label = (round(8 * z), round(22 * z))
            banner = (round(12 * z) + w, at_label[1] + base + round(2 * z))
            cv2.rectangle(out, (round(4 * z), at_label[1] - h - round(5 * z)), banner,
                          (0, 0, 0), -1)
        self._n += 1
        boxes = tracks.boxes
        ids = np.asarray(tracks.ids)
        if ids.dtype.kind == "f" and (np.abs(ids) < 2**53).all() and \
                (ids == np.round(ids)).all():  # (past 2**53 an int64 read 1e20 as -2**63)
            ids = ids.astype(np.int64)  # (a float identity was labelled "3.0"; written as 3)
        covs = getattr(tracks, "covs", None)
        # a box or point that is not finite has nowhere to be drawn (OpenCV failed on it, and
        # the annotated video with it); one far outside the image is drawn clipped to where
        # OpenCV's integers reach, off the image as it is
        geometry = boxes if boxes is not None else tracks.points[:, :2]  # type: ignore[index]
        keep = np.isfinite(geometry).all(1)
        if not keep.all():
            ids, geometry = ids[keep], geometry[keep]
            covs = covs[keep] if covs is not None else None
        reach = 16.0 * max(out.shape[:2])
        geometry = np.clip(geometry, -reach, reach)
        if boxes is not None:
            boxes = geometry
        # tracks without boxes have points
        centres = (boxes[:, :2] + boxes[:, 2:]) / 2 if boxes is not None else geometry
        self._remember(ids.tolist(), np.round(centres).astype(np.int32))
        present = set(ids.tolist())
        for i, slot in self._slot.items():
            # a trail ends with its track: drawn only while the identity is in the frame (its
            # centres are kept for ``trail`` frames, so that it goes on if the track returns)
            if i in present:
                pts = self._window(slot)
                if len(pts) > 1:
                    cv2.polylines(out, [pts.reshape(-1, 1, 2)], False, id_colour(i), thick,
                                  cv2.LINE_AA)
        if covs is not None:
            # every ellipse's axes and angle in one call (eigh a track took 6 of the 18 ms of
            # a frame of 520 particles); a covariance that is not finite draws none
            c2 = np.asarray(covs, dtype=float)[:, :2, :2]
            has_ellipse = np.isfinite(c2).all(axis=(1, 2))
            lams, vecs = np.zeros((len(c2), 2)), np.zeros((len(c2), 2, 2))
            if has_ellipse.any():
                lams[has_ellipse], vecs[has_ellipse] = np.linalg.eigh(c2[has_ellipse])
            semi = np.minimum(self.nsigma * np.sqrt(np.maximum(lams, 0.0)), reach)
            angles = np.degrees(np.arctan2(vecs[:, 1, 1], vecs[:, 0, 1]))
        font, scale = cv2.FONT_HERSHEY_SIMPLEX, 0.5 * z
        gap, dot, halo = round(4 * z), round(3 * z), max(3, round(3 * z))  # (once a frame)
        if len(self._sizes) > 16384:  # (bounded on a long video of many identities)
            self._sizes.clear()
        known = self._sizes
        sizes = [known.get((i, scale, thin)) or known.setdefault(
            (i, scale, thin), cv2.getTextSize(str(i), font, scale, thin)) for i in ids.tolist()]
        numbered = self.labels
        if numbered is None:
            cover = sum((tw + 2 * thick) * (th + tb + 2 * thick) for (tw, th), tb in sizes)
            line = LABEL_COVER if self._numbered else LABEL_COVER / 2
            numbered = self._numbered = cover <= line * H * W
        # every track's whole pixels at once (as int(round(v)) each: half to even), and
        # plain Python numbers for OpenCV
        at = np.round(centres).astype(int).tolist()
        cut = np.trunc(centres).astype(int).tolist()  # (as int(v): toward zero)
        if covs is not None:
            axes_px = np.maximum(np.round(semi).astype(int), 1)[:, ::-1].tolist()
            turned = angles.tolist()
        corners = np.round(boxes).astype(int).tolist() if boxes is not None else None
        # the numbers after every box and trail: a box drawn after another's number covered
        # it (track 9's under track 19's top edge)
        numbers: list[tuple[str, tuple[int, int], tuple[int, int, int]]] = []
        for k, i in enumerate(ids.tolist()):
            c = id_colour(i)
            if covs is not None and has_ellipse[k]:
                cv2.ellipse(out, at[k], axes_px[k], turned[k], 0, 360, c, thin, cv2.LINE_AA)
            (tw, th), tb = sizes[k]
            if corners is not None:
                x0, y0, x1, y1 = corners[k]
                cv2.rectangle(out, (x0, y0), (x1, y1), c, thick)
                x, y = x0, y0 - gap  # above the box
                top = banner[1] if x < banner[0] else 0
                if y - th < top:  # off the image, or under the frame's label: inside, at the top
                    y = max(y0, top) + th + gap
            else:
                cv2.circle(out, at[k], dot, c, -1)
                x, y = cut[k][0] + gap, cut[k][1] - gap
                top = banner[1] if x < banner[0] else 0
                if y - th < top:  # under the frame's label (hidden there), or off the image:
                    y = top + th + gap  # below it, as a box's number goes
            if not numbered:
                continue
            # a box or point wholly off the image has no number: pulled inside, it stood at
            # the edge over nothing
            if corners is not None:
                if x1 < 0 or y1 < 0 or x0 >= W or y0 >= H:  # (no pixel of it drawn)
                    continue
            elif not (0 <= at[k][0] < W and 0 <= at[k][1] < H):
                continue
            # the whole number inside the image (a box past the left edge showed a sliver)
            org = (min(max(x, 0), max(W - tw, 0)), min(max(y, th), max(H - tb, th)))
            numbers.append((str(i), org, c))
        for text, org, _ in numbers:
            cv2.putText(out, text, org, font, scale, (0, 0, 0), halo, cv2.LINE_AA)
        for text, org, c in numbers:  # (each halo under every number, none over one)
            cv2.putText(out, text, org, font, scale, c, thin, cv2.LINE_AA)
        if label:
            for colour, width in (((0, 0, 0), thin + 2 * max(1, round(z))),
                                  ((255, 255, 255), thin)):
                cv2.putText(out, label, at_label, cv2.FONT_HERSHEY_SIMPLEX, label_scale,
                            colour, width, cv2.LINE_AA)
        return out

    def _window(self, slot: int) -> np.ndarray:
        """The centres of a slot's trail, oldest first, ``(k, 2)``: a view of the ring."""
        n, C = int(self._count[slot]), self._C
        head = n % C if n > C else 0  # (n > C only once the ring is the whole trail; C > 0)
        return self._buf[slot, head:head + min(n, C)]

    def _lay_out(self, C: int) -> None:
        """The slots as rings of ``C`` centres, each slot's last ``C`` centres (or fewer)
        kept, oldest first, from its start."""
        buf = np.zeros((len(self._count), 2 * C, 2), np.int32)
        count = np.zeros_like(self._count)
        for slot in self._slot.values() if C else ():
            kept = self._window(slot)[-C:]
            buf[slot, :len(kept)] = kept
            count[slot] = len(kept)
        self._buf, self._count, self._C = buf, count, C

    def _remember(self, ids: list[int], at: np.ndarray) -> None:
        """Add this frame's centres ``at`` (whole pixels) to the trails of ``ids``, and forget
        the identities unseen for ``trail`` frames."""
        if self.trail != self._laid:  # changed since the last frame: every trail follows it
            if int(self.trail) < 0:
                raise ValueError(f"trail must be a number of frames >= 0; got {self.trail}")
            self.trail = self._laid = int(self.trail)  # (a whole number, as when made)
            self._lay_out(min(self.trail, max(self._C, 32)))
        slots = []
        for i in ids:
            slot = self._slot.get(i)
            if slot is None:
                if not self._free:  # twice the slots, the new ones free
                    old = len(self._count)
                    grow = max(64, old)
                    self._buf = np.concatenate(
                        [self._buf, np.zeros((grow,) + self._buf.shape[1:], np.int32)])
                    self._count = np.concatenate([self._count, np.zeros(grow, np.int64)])
                    self._free = list(range(old + grow - 1, old - 1, -1))
                slot = self._slot[i] = self._free.pop()
            slots.append(slot)
            self._last[i] = self._n
        T = self.trail
        if T and slots:
            s = np.asarray(slots)
            twice = len(set(slots)) < len(slots)
            # the ring grows before a trail of fewer centres than the trail would wrap
            need = int((self._count[s] + (np.bincount(s)[s] if twice else 1)).max())
            if self._C < T and need > self._C:
                self._lay_out(min(T, max(2 * self._C, 1 << (need - 1).bit_length())))
            C = self._C
            if not twice:
                j = self._count[s] % C
                self._buf[s, j] = at
                self._buf[s, j + C] = at
                self._count[s] += 1
            else:  # an identity twice in one frame: each of its centres, in turn
                for slot, xy in zip(slots, at):
                    j = self._count[slot] % C
                    self._buf[slot, j] = self._buf[slot, j + C] = xy
                    self._count[slot] += 1
        for i in [i for i, n in self._last.items() if self._n - n > T]:
            slot = self._slot.pop(i)
            del self._last[i]
            self._count[slot] = 0
            self._free.append(slot)


class AnnotatedVideo:
    """A sink (:class:`~vistrack.io.tracks.Sink`) that draws each frame's tracks with an
    :class:`Annotator` and writes the frames to an MP4 at ``fps``
    (:class:`~vistrack.io.VideoWriter`), each labelled with its frame index.

    Parameters
    ----------
    path : str or Path
        The video to write (opened at the first frame).
    fps : float
        Frames per second of the video.
    annotator : Annotator, optional
        How to draw (default ``Annotator()``).

    Raises
    ------
    ValueError
        If ``fps`` is not a finite number > 0.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from vistrack.io import VideoReader
    >>> from vistrack.types import Frame, Tracks
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "annotated.mp4"
    >>> video = AnnotatedVideo(path, fps=10)
    >>> for k in range(1, 4):
    ...     video.write(Frame(k, (k - 1) / 10, np.zeros((48, 64, 3), np.uint8)), Tracks.empty())
    >>> video.close()
    >>> len(VideoReader(path))
    3
    """

    def __init__(self, path: str | os.PathLike, fps: float, annotator: Annotator | None = None):
        from ..io import VideoWriter, partial_path

        self.path = Path(path)
        self.annotator = annotator or Annotator()
        # frames go to a partial file, renamed over ``path`` when the video is complete
        self._part = partial_path(self.path)
        self._writer = VideoWriter(self._part, fps, name=self.path)
        self._size: tuple[int, int] | None = None

    def write(self, frame: Frame, tracks: Tracks) -> None:
        """Draw ``tracks`` on ``frame.image`` and write it.

        Parameters
        ----------
        frame : Frame
            The frame, with its image (all of one size).
        tracks : Tracks
            Its tracks.

        Raises
        ------
        ValueError
            If the frame has no image, or its size differs from the first frame's.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> from vistrack.types import Frame, Tracks
        >>> video = AnnotatedVideo(pathlib.Path(tempfile.mkdtemp()) / "a.mp4", fps=10)
        >>> video.write(Frame(1, 0.0), Tracks.empty())
        Traceback (most recent call last):
        ...
        ValueError: AnnotatedVideo draws on images; frame 1 has none
        """
        if frame.image is None:
            raise ValueError(f"AnnotatedVideo draws on images; frame {frame.index} has none")
        size = frame.image.shape[1::-1]
        if self._size is None:
            self._size = size
        elif size != self._size:  # (the writer counted its frames: "frame 3" for frame 103)
            raise ValueError(f"{self.path}: frame {frame.index} is {size[0]}x{size[1]}; the "
                             f"video is {self._size[0]}x{self._size[1]}")
        self._writer.write(self.annotator.draw(frame.image, tracks,
                                               label=f"frame {frame.index}"))

    def close(self) -> None:
        """Finish the video file: it replaces any earlier ``path`` only now, complete. With
        no frame written there is no video (an MP4 needs a frame's size): no file is made,
        and an earlier ``path`` is left as it was (:func:`~vistrack.pipeline.track_video`
        refuses a run of no frames before it closes its outputs).

        Examples
        --------
        >>> import tempfile, pathlib
        >>> video = AnnotatedVideo(pathlib.Path(tempfile.mkdtemp()) / "a.mp4", fps=10)
        >>> video.close()
        >>> video.path.exists()   # no frame: no file
        False
        """
        from ..io.atomic import commit_partial

        self._writer.close()
        if self._part.exists():
            commit_partial(self._part, self.path)

    def abort(self) -> None:
        """Give the video up (a run that failed): the frames written are removed, and an
        earlier ``path`` is left as it was."""
        self._writer.abandon()
        self._part.unlink(missing_ok=True)
