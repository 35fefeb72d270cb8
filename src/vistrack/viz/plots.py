"""Plots of filter and smoother runs, in the style of the seeds' figures.

The filter figures draw on a given matplotlib ``ax`` and return it; ``plot_trajectories`` makes
its own figure and can save it. None calls ``plt.show()``.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

from .._pool import counted

if TYPE_CHECKING:
    import os

    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from numpy.typing import ArrayLike

    from ..types import Frame, Tracks

__all__ = ["covariance_ellipse", "plot_estimates_1d", "plot_track_2d", "plot_trajectories",
           "plot_hota_alpha", "plot_timeline", "TrajectoryPlot"]


def _label(name: str, limit: int = 60) -> str:
    """A name (a sequence's, a video's) as a title or legend shows it: its ``$`` taken
    literally, not as matplotlib's mathematics (``a$b$c`` showed an italic b, ``p$^$q`` failed
    to draw), and a name longer than ``limit`` characters cut in the middle, so that what
    follows it in a title stays inside the figure."""
    if len(name) > limit:
        name = name[:limit // 2 - 1] + "…" + name[-(limit - limit // 2):]
    return name.replace("$", r"\$")


def _finish(ax: Axes, xlabel: str, ylabel: str, title: str | None) -> Axes:
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.legend(loc="best", fontsize=8)
    return ax


def covariance_ellipse(mean: ArrayLike, cov: ArrayLike, *, nsigma: float = 1.0,
                       points: int = 64) -> np.ndarray:
    r"""Points ``(points, 2)`` on the ``nsigma`` contour of a 2-D Gaussian ``N(mean, cov)``.

    With :math:`\mathrm{cov} = V \operatorname{diag}(w) V'`, the points are
    :math:`\mu + n_\sigma V \operatorname{diag}(\sqrt{w}) (\cos a, \sin a)'` for ``points``
    angles :math:`a` from 0 to :math:`2\pi` (both ends: the contour is closed).

    Parameters
    ----------
    mean : (2,) array_like
        The centre.
    cov : (2, 2) array_like
        The covariance, symmetric positive semi-definite (negative eigenvalues count as 0).
    nsigma : float
        The contour's Mahalanobis distance.
    points : int
        Points on it.

    Returns
    -------
    (points, 2) ndarray
        The contour.

    Raises
    ------
    ValueError
        If ``mean`` is not ``(2,)`` or ``cov`` not ``(2, 2)``.

    Examples
    --------
    Standard deviations 2 along x and 1 along y, at 2 sigma:

    >>> covariance_ellipse([1.0, 2.0], np.diag([4.0, 1.0]), nsigma=2, points=5).round(3) + 0.0
    array([[ 1.,  4.],
           [ 5.,  2.],
           [ 1.,  0.],
           [-3.,  2.],
           [ 1.,  4.]])
    """
    mean = np.asarray(mean, dtype=float)
    cov = np.asarray(cov, dtype=float)
    if mean.shape != (2,) or cov.shape != (2, 2):
        raise ValueError(f"need a 2-D mean (2,) and covariance (2, 2); got {mean.shape}, "
                         f"{cov.shape}")
    w, V = np.linalg.eigh(cov)
    a = np.linspace(0.0, 2.0 * np.pi, points)
    circle = np.stack([np.cos(a), np.sin(a)], axis=1)
    return mean + nsigma * (circle * np.sqrt(np.clip(w, 0.0, None))) @ V.T


def plot_estimates_1d(
    ax: Axes,
    t: ArrayLike,
    *,
    truth: ArrayLike | None = None,
    measurements: ArrayLike | None = None,
    pred_mean: ArrayLike | None = None,
    pred_std: ArrayLike | None = None,
    mean: ArrayLike | None = None,
    std: ArrayLike | None = None,
    nsigma: float = 3.0,
    title: str | None = None,
    mean_label: str = r"corrected $\bar{x}_i^+$",
) -> Axes:
    """The seeds' 1-D figure: "The o-s give state, x-s measurement. The \\*-s give x̄ᵢ⁻, +-s give
    x̄ᵢ⁺, vertical bars are 3 standard deviation bars".

    All series are arrays of shape (T,); NaN points are not drawn. ``mean_label`` names the
    ``mean`` series (e.g. "smoothed"). Returns ``ax``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    t : (T,) array_like
        Times; the predicted and corrected series are drawn a little left and right of them.
    truth, measurements : (T,) array_like, optional
        The states (circles) and measurements (crosses).
    pred_mean, pred_std : (T,) array_like, optional
        The predicted means (stars) and their standard deviations.
    mean, std : (T,) array_like, optional
        The corrected (or smoothed) means (pluses) and their standard deviations.
    nsigma : float
        Half-length of the error bars, in standard deviations.
    title : str, optional
        The axes' title.
    mean_label : str
        Legend of the ``mean`` series.

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``, labelled, with a legend.

    Examples
    --------
    >>> from matplotlib.figure import Figure
    >>> ax = Figure().subplots()
    >>> _ = plot_estimates_1d(ax, [0.0, 1.0, 2.0], truth=[0, 1, 2], measurements=[0.1, 1.2, 1.9],
    ...                       mean=[0.0, 1.1, 2.0], std=[0.3, 0.2, 0.2])
    >>> [t.get_text() for t in ax.get_legend().get_texts()][:2], ax.get_xlabel()
    (['state', 'measurement'], 'time')
    """
    t = np.asarray(t, dtype=float)
    off = 0.12 * (np.median(np.diff(t)) if t.size > 1 else 1.0)
    if truth is not None:
        ax.plot(t, truth, "o", mfc="none", color="k", label="state")
    if measurements is not None:
        ax.plot(t, measurements, "x", color="tab:green", label="measurement")
    for tt, mu, sd, marker, ms, color, label in (
        (t - off, pred_mean, pred_std, "*", 6, "tab:blue", r"predicted $\bar{x}_i^-$"),
        (t + off, mean, std, "+", 9, "tab:red", mean_label),
    ):
        if mu is None:
            continue
        ax.plot(tt, mu, marker, color=color, ms=ms, label=label)
        if sd is not None:
            ax.errorbar(tt, mu, yerr=nsigma * np.asarray(sd), fmt="none", ecolor=color,
                        elinewidth=0.8, capsize=2)
    return _finish(ax, "time", "position", title)


def plot_track_2d(
    ax: Axes,
    *,
    truth: ArrayLike | None = None,
    measurements: ArrayLike | None = None,
    means: ArrayLike | None = None,
    covs: ArrayLike | None = None,
    label: str = "estimate",
    color: str = "tab:red",
    nsigma: float = 1.0,
    title: str | None = None,
) -> Axes:
    """A 2-D track: true path, measurements, estimated positions and their ``nsigma`` ellipses.

    ``truth``, ``measurements``, ``means`` are ``(T, >=2)`` arrays whose first two columns are the
    position; ``covs`` is ``(T, >=2, >=2)`` and its top-left 2x2 block is drawn. Returns ``ax``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    truth, measurements, means : (T, >=2) array_like, optional
        The true path (squares), the measurements (stars) and the estimates (crosses).
    covs : (T, >=2, >=2) array_like, optional
        The estimates' covariances; their ``nsigma`` ellipses are drawn (with ``means``).
    label, color : str
        Legend and colour of the estimates.
    nsigma : float
        The ellipses' size, in standard deviations.
    title : str, optional
        The axes' title.

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``, with equal scales on both axes.

    Examples
    --------
    >>> from matplotlib.figure import Figure
    >>> ax = Figure().subplots()
    >>> means = np.c_[np.arange(3.0), np.zeros(3)]
    >>> _ = plot_track_2d(ax, means=means, covs=np.tile(0.1 * np.eye(2), (3, 1, 1)))
    >>> len(ax.lines)   # the estimates and three ellipses
    4
    """
    if truth is not None:
        tr = np.asarray(truth)
        ax.plot(tr[:, 0], tr[:, 1], "ks-", ms=4, mfc="none", lw=0.8, label="true")
    if measurements is not None:
        ys = np.asarray(measurements)
        ax.plot(ys[:, 0], ys[:, 1], "g*", label="observed")
    if means is not None:
        ms = np.asarray(means)
        ax.plot(ms[:, 0], ms[:, 1], "x-", color=color, lw=1.0, label=label)
        if covs is not None:
            for mu, P in zip(ms, np.asarray(covs), strict=True):
                e = covariance_ellipse(mu[:2], P[:2, :2], nsigma=nsigma)
                ax.plot(e[:, 0], e[:, 1], "-", color=color, lw=0.7, alpha=0.8)
    ax.set_aspect("equal", adjustable="box")
    return _finish(ax, "x", "y", title)


def _import_agg() -> None:
    """Import what a figure saved to a file is drawn with: matplotlib's Figure and its Agg
    canvas (no pyplot)."""
    import matplotlib.backends.backend_agg  # noqa: F401
    import matplotlib.figure  # noqa: F401


_LABELLED = 100  # plot_trajectories labels each path with its identity up to this many


def plot_trajectories(frames: ArrayLike, ids: ArrayLike, centres: ArrayLike,
                      background: ArrayLike | None = None, path: str | os.PathLike | None = None,
                      *, title: str | None = None) -> Figure:
    """Every track's path of centres ``(N, 2)`` (rows of ``frames`` and ``ids``), each in its
    identity's colour in the annotated video (:func:`vistrack.viz.annotate.id_colour`) and,
    when there are at most 100 tracks, labelled with its identity at its last centre (the
    dot), over a dimmed ``background`` image (RGB or grey) when given; saved to ``path`` (PNG)
    when given. Returns the figure.

    Parameters
    ----------
    frames, ids : (N,) array_like
        Frame and identity of each row (any order; each track is drawn in frame order).
    centres : (N, 2) array_like
        Centre ``x, y`` of each row, in pixels.
    background : (H, W, 3) or (H, W) array_like, optional
        An image under the paths (RGB or grey); without it the y axis points down, as in an
        image.
    path : str or Path, optional
        Save the figure there (PNG, 100 dpi). The figure is then drawn without pyplot: no
        backend is switched and pyplot keeps no figure open.
    title : str, optional
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (a pyplot figure without ``path``; pyplot does not know it with one).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "paths.png"
    >>> fig = plot_trajectories([1, 2, 1, 2], [1, 1, 2, 2], [[0, 0], [1, 1], [5, 5], [6, 5]],
    ...                         path=path)
    >>> paths, dots = fig.axes[0].collections   # every path one artist, every end dot one
    >>> [p.tolist() for p in paths.get_segments()], dots.get_offsets().tolist(), path.exists()
    ([[[0.0, 0.0], [1.0, 1.0]], [[5.0, 5.0], [6.0, 5.0]]], [[1.0, 1.0], [6.0, 5.0]], True)
    """
    from matplotlib import patheffects
    from matplotlib.collections import LineCollection

    from .annotate import id_colour

    fr, ids_, c = np.asarray(frames), np.asarray(ids), np.asarray(centres, dtype=float)
    # (a third centre beside two frames was dropped; other lengths failed in numpy's words)
    if c.ndim != 2 or c.shape[1] != 2 or not len(fr) == len(ids_) == len(c):
        raise ValueError(f"frames, ids and centres must be one row each, centres (N, 2); got "
                         f"{len(fr)} frames, {len(ids_)} ids and centres of shape {c.shape}")
    bad = ~np.isfinite(c).all(axis=1)
    if bad.any():
        # a track's NaN last centre was its end dot and label's place (neither was drawn;
        # one with a single finite centre vanished): such rows are left out, and said
        warnings.warn(f"{int(bad.sum())} of the {len(c)} centres are not finite (NaN or "
                      "infinite boxes): left out of the plot", RuntimeWarning, stacklevel=2)
        fr, ids_, c = fr[~bad], ids_[~bad], c[~bad]
    if path is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(9, 7))
    else:  # drawn and saved without pyplot: no backend switched, no figure left open
        from matplotlib.figure import Figure

        fig = Figure(figsize=(9, 7))
    ax = fig.subplots()
    image, bg = None, None if background is None else np.asarray(background)
    if bg is not None:
        image = ax.imshow(bg, cmap="gray", alpha=0.45)
    frames, ids = fr, ids_
    order = np.lexsort((frames, ids))
    starts = np.flatnonzero(np.diff(ids[order])) + 1
    paths = np.split(c[order], starts) if len(order) else []
    # every path one artist, and every end dot another: two artists a track (two thousand
    # tracks in an hour of video) took 66 MB more to draw, and four times as long
    track_ids = ids[order][np.r_[0, starts]] if len(order) else ids[:0]
    # the annotated video's colour of each identity (BGR there), so a path and its boxes match
    colours = np.array([id_colour(i)[::-1] for i in track_ids], float).reshape(-1, 3) / 255
    ax.add_collection(LineCollection(paths, colors=colours, linewidths=1.5))
    last = np.array([p[-1] for p in paths]).reshape(-1, 2)
    ax.scatter(last[:, 0], last[:, 1], s=9, c=colours, zorder=2.5)
    ax.autoscale_view()
    if background is None:
        ax.invert_yaxis()
        ax.set_aspect("equal", adjustable="box")
    elif bg is not None and len(c):
        # the view: the image and the paths near it, up to its own size past each edge (one
        # centre at x = 1e5 made a 768-pixel frame a strip); what lies beyond is said
        H, W = bg.shape[:2]
        lo, hi = np.array([-0.5 - W, -0.5 - H]), np.array([2 * W - 0.5, 2 * H - 0.5])
        far = ((c < lo) | (c > hi)).any(axis=1)
        if far.any():
            warnings.warn(f"{int(far.sum())} of the {len(c)} centres lie more than the "
                          f"image's size ({W} x {H}) outside it: beyond the plot's view",
                          RuntimeWarning, stacklevel=2)
        near = c[~far]
        x0, y0 = np.minimum(near.min(axis=0), -0.5) if len(near) else (-0.5, -0.5)
        x1, y1 = np.maximum(near.max(axis=0), [W - 0.5, H - 0.5]) if len(near) else (
            W - 0.5, H - 0.5)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y1, y0)
    ax.set_xlabel("x (pixels)")
    ax.set_ylabel("y (pixels)")
    if title:
        ax.set_title(title)
    if len(paths) <= _LABELLED:
        labels = [str(i) for i in track_ids]
        fig.tight_layout()  # (the axes' place, which the labels' offsets are measured in)
        for (x, y), text, col, off in zip(last, labels, colours,
                                          _label_offsets(ax, last, labels, 7)):
            ax.annotate(text, (x, y), xytext=off, textcoords="offset points", fontsize=7,
                        color=col, fontweight="bold", path_effects=[
                            patheffects.withStroke(linewidth=2, foreground="black")])
    if path is not None and image is not None and bg is not None and (
            bg.ndim == 2 or (bg.ndim == 3 and bg.shape[2] == 3)):
        # saved with the background put under the drawing rather than drawn by matplotlib,
        # which resamples an image in floating point: 26-37 MB for a 768x576 frame, at the
        # end of a run, against a few MB here (the hidden image still sets the axes' limits)
        image.set_visible(False)
        fig.tight_layout()
        _save_over(fig, ax, image, bg, path)
        image.set_visible(True)  # the figure returned shows it as before
    else:
        fig.tight_layout()
        if path is not None:
            fig.savefig(path, dpi=100)
    return fig


def _label_offsets(ax: Any, xy: np.ndarray, labels: list[str], size: float
                   ) -> list[tuple[float, float]]:
    """Offsets in points of each label from its point ``xy`` (data), in turn, so that no
    label covers one placed before it where a place is free: up and to the right, else below,
    to the left, or further up or down; the first such place inside the axes (a track that
    ends at the image's right edge is labelled to its left, not across the frame), else the
    first free one, else the first. Sizes are estimated from the font size (bold digits are
    about 0.7 of it wide, a line about 1.2 of it high)."""
    ax.apply_aspect()
    scale = 72 / ax.figure.dpi
    pts = ax.transData.transform(np.asarray(xy, float).reshape(-1, 2)) * scale
    frame = ax.get_window_extent()
    x0, y0, x1, y1 = (v * scale for v in (frame.x0, frame.y0, frame.x1, frame.y1))
    placed: list[tuple[float, float, float, float]] = []
    out = []
    for (px, py), text in zip(pts, labels):
        w, h = 0.7 * size * len(text) + 2, 1.25 * size
        tries = [(dx, dy) for k in range(4) for dy in (3 + k * h, -3 - (k + 1) * h)
                 for dx in (3, -3 - w)]
        boxes = [(px + dx, py + dy, px + dx + w, py + dy + h) for dx, dy in tries]
        free = [k for k, box in enumerate(boxes)
                if not any(box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3]
                           for b in placed)]
        inside = [k for k in free if x0 <= boxes[k][0] and boxes[k][2] <= x1
                  and y0 <= boxes[k][1] and boxes[k][3] <= y1]
        k = (inside or free or [0])[0]
        placed.append(boxes[k])
        out.append(tries[k])
    return out


def plot_hota_alpha(results: dict[str, Any], path: str | os.PathLike | None = None, *,
                    zero_distance: float | None = None) -> Figure:
    """HOTA, DetA and AssA over the localisation threshold α (TrackEval's curves), one line
    per sequence of ``results`` and a thick black one for ``"COMBINED"`` when there; saved to
    ``path`` (PNG) when given, without pyplot. Returns the figure.

    Parameters
    ----------
    results : dict of str to MOTCounts
        Scores by sequence (:func:`vistrack.evaluation.evaluate_files`).
    path : str or Path, optional
        Save the figure there (PNG, 100 dpi).
    zero_distance : float, optional
        The results scored positions by distance (``evaluate_mot(zero_distance=)``): α is a
        threshold on the similarity ``1 - d / zero_distance``, not on the IoU, and the axis
        says so.

    Examples
    --------
    >>> from vistrack.evaluation.mot import MOTCounts, evaluate_mot
    >>> from vistrack.io.motchallenge import MOTTable
    >>> gt = MOTTable.from_rows([(1, 1, 0, 0, 10, 20), (2, 1, 1, 0, 10, 20)])
    >>> fig = plot_hota_alpha({"a": evaluate_mot(gt, gt)})
    >>> [ax.get_title() for ax in fig.axes], fig.axes[0].lines[0].get_ydata()[0]
    (['HOTA', 'DetA', 'AssA'], np.float64(100.0))
    """
    from matplotlib.figure import Figure

    from ..evaluation.mot import ALPHAS

    fig = Figure(figsize=(12, 4))
    axes = fig.subplots(1, 3, sharey=True)
    names = [n for n in results if n != "COMBINED"] + (["COMBINED"] if "COMBINED" in results
                                                      else [])
    colours = _tab20(len(names))
    for ax, metric in zip(axes, ("HOTA", "DetA", "AssA")):
        for k, name in enumerate(names):
            y = 100 * np.asarray(getattr(results[name], f"{metric}_alpha"), dtype=float)
            # clip_on off and above the frame (whose zorder is 2.5; a line of the same was
            # drawn under it): a score of 0 or 100 lies on the axes' frame, and was hidden
            if name == "COMBINED":
                ax.plot(ALPHAS, y, color="black", linewidth=2.5, label=name, clip_on=False,
                        zorder=3.5)
            else:
                ax.plot(ALPHAS, y, color=colours[k], linewidth=1, label=_label(name, 40),
                        clip_on=False, zorder=3)
        ax.set_title(metric)
        ax.set_xlabel("localisation threshold α (IoU)" if zero_distance is None else
                      f"localisation threshold α (1 - distance / {zero_distance:g})")
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 100)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("score (%)")
    if len(names) - ("COMBINED" in results) <= 20:  # (COMBINED counted among 20 left
        # twenty sequences unnamed, the legend saying "named up to 20")
        # beside the panels, where it hides no curve (inside the last one, 20 names covered
        # a third of its width)
        # the lines given, not collected: matplotlib leaves out a label that starts with
        # "_" (a sequence named _night had a curve and no name)
        lines = axes[-1].get_lines()
        axes[-1].legend(lines, [line.get_label() for line in lines], fontsize=7,
                        loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0)
    else:
        # too many to name (their colours repeat): the legend says what the lines are (it
        # was left out, without a word, and COMBINED's line with it)
        from matplotlib.lines import Line2D

        seqs = len(names) - ("COMBINED" in results)
        handles = [Line2D([], [], color="grey", linewidth=1,
                          label=f"{seqs} sequences (named up to 20)")]
        if "COMBINED" in results:
            handles.append(Line2D([], [], color="black", linewidth=2.5, label="COMBINED"))
        axes[-1].legend(handles=handles, fontsize=7, loc="upper left",
                        bbox_to_anchor=(1.02, 1.0), borderaxespad=0)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=100)
    return fig


def plot_timeline(matches: Any, path: str | os.PathLike | None = None, *,
                  title: str = "") -> Figure:
    """A timeline of every ground-truth object: one row per object (in the order they first
    appear), time across, each frame coloured by the predicted identity that covers the
    object there (the annotated video's colour of that identity; light grey where it is
    missed), and a black mark where the identity switches. Saved to ``path`` (PNG) when
    given, without pyplot. Returns the figure.

    Parameters
    ----------
    matches : Matches
        From :func:`vistrack.evaluation.clear_matches`.
    path : str or Path, optional
        Save the figure there (PNG, 100 dpi).
    title : str
        Put before the counts in the title (the sequence's name).

    Examples
    --------
    >>> from vistrack.evaluation import Matches
    >>> m = Matches(frames=np.array([1, 2, 3, 1, 2]), gt_ids=np.array([5, 5, 5, 6, 6]),
    ...             pred_ids=np.array([7, 8, 8, -1, 9]),
    ...             switches=np.array([False, True, False, False, False]),
    ...             matched=np.array([True, True, True, False, True]))
    >>> ax = plot_timeline(m, title="demo").axes[0]
    >>> [t.get_text() for t in ax.get_yticklabels()], ax.get_title()
    (['5', '6'], 'demo: 2 objects, 1 identity switch')
    """
    from matplotlib.collections import PolyCollection
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    from .annotate import id_colour

    frames, gts = np.asarray(matches.frames), np.asarray(matches.gt_ids)
    preds, switches = np.asarray(matches.pred_ids), np.asarray(matches.switches, bool)
    hit = np.asarray(matches.matched, bool)  # (a track numbered -1 or below is no miss)
    objects, first = np.unique(gts, return_index=True)
    objects = objects[np.argsort(first, kind="stable")]  # in the order they appear
    row = {int(g): k for k, g in enumerate(objects)}
    n = len(objects)
    # (at least 2.4 inches: at 1.76, with no object, the y label was cut to "ground-truth
    # objec")
    fig = Figure(figsize=(12, min(40.0, max(2.4, 1.6 + 0.16 * n))))
    ax = fig.subplots()
    boxes, colours = [], []
    order = np.lexsort((frames, gts))
    f, g, p, h = frames[order], gts[order], preds[order], hit[order]
    # runs: the same object, the same predicted id (or missed), consecutive frames
    new = (np.r_[True, (g[1:] != g[:-1]) | (p[1:] != p[:-1]) | (h[1:] != h[:-1])
                 | (f[1:] != f[:-1] + 1)]
           if len(f) else np.zeros(0, bool))  # no ground truth scored: no runs
    starts = np.flatnonzero(new)
    ends = np.r_[starts[1:], len(f)]
    for a, b in zip(starts, ends):
        y = row[int(g[a])]
        x0, x1 = f[a] - 0.5, f[b - 1] + 0.5
        boxes.append([(x0, y - 0.4), (x1, y - 0.4), (x1, y + 0.4), (x0, y + 0.4)])
        if not h[a]:
            colours.append((0.85, 0.85, 0.85))
        else:
            b_, g_, r_ = id_colour(int(p[a]))
            colours.append((r_ / 255, g_ / 255, b_ / 255))
    ax.add_collection(PolyCollection(boxes, facecolors=colours, edgecolors="none"))
    sw = np.flatnonzero(switches)
    ax.scatter(frames[sw], [row[int(x)] for x in gts[sw]], marker="|", s=120, c="black",
               linewidths=1.5, zorder=3)
    if len(frames):
        ax.set_xlim(frames.min() - 1, frames.max() + 1)
    else:
        ax.set_xticks([])
        ax.text(0.5, 0.5, "no ground-truth box to score", transform=ax.transAxes,
                ha="center", va="center", color="0.4")
    ax.set_ylim(max(n, 1) - 0.5, -0.5)  # one empty row when no object was scored
    step = max(1, int(np.ceil(n / 60)))
    ax.set_yticks(np.arange(0, n, step), [str(int(o)) for o in objects[::step]],
                  fontsize=7 if n > 30 else 9)
    ax.set_xlabel("frame (colour: the predicted identity covering the object; grey: missed; "
                  "black mark: an identity switch)")
    ax.set_ylabel("ground-truth object")
    k = int(switches.sum())
    counts = f"{counted(n, 'object')}, {counted(k, 'identity switch', 'identity switches')}"
    ax.set_title(f"{_label(title)}: {counts}" if title else counts)
    if len(frames):  # frames are whole (with none, the locator put ticks at ±0.05 back)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.grid(axis="x", alpha=0.3)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=100)
    return fig


def _tab20(n: int) -> list[Any]:
    """``n`` colours of matplotlib's tab20, its ten dark hues first and then their light
    pairs, repeating past 20 (taken in order, the first two were dark and light blue, the
    next two orange: neighbours told apart by lightness alone)."""
    import matplotlib

    tab = matplotlib.colormaps["tab20"]
    return [tab(2 * (k % 20) if k % 20 < 10 else 2 * (k % 20 - 10) + 1) for k in range(n)]


def _save_over(fig: Figure, ax: Axes, image: Any, background: np.ndarray,
               path: str | os.PathLike) -> None:
    """Save ``fig`` (PNG, 100 dpi) drawn over ``background``, an RGB or grey image shown by
    ``image`` (an ``AxesImage`` of ``ax``, hidden, of alpha 0.45), as matplotlib would draw it:
    grey levels stretched from their least to their greatest, the image blended over the axes'
    face colour."""
    import cv2
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.image import imsave

    fig.set_dpi(100)
    canvas = FigureCanvasAgg(fig)
    faces = [(patch, patch.get_alpha()) for patch in (fig.patch, ax.patch)]
    for patch, _ in faces:
        patch.set_alpha(0.0)  # drawn below instead
    try:
        canvas.draw()
    finally:
        for patch, alpha in faces:
            patch.set_alpha(alpha)
    top = np.asarray(canvas.buffer_rgba())  # straight (not premultiplied) alpha
    h, w = top.shape[:2]
    # what lies under the drawing, in bytes: the figure's face, the axes' face, the image
    out = np.empty((h, w, 3), np.uint8)
    out[:] = _bytes(fig.get_facecolor())
    face = _bytes(ax.get_facecolor())
    (x0, y0), (x1, y1) = ax.bbox.get_points()
    box = (slice(max(0, round(h - y1)), round(h - y0)), slice(max(0, round(x0)), round(x1)))
    out[box] = face
    # the image's corners in pixels (display coordinates have y up; the buffer's rows go down)
    left, right, bottom, top_ = image.get_extent()
    (xa, ya), (xb, yb) = ax.transData.transform([(left, bottom), (right, top_)])
    c0, c1 = round(min(xa, xb)), round(max(xa, xb))
    r0, r1 = round(h - max(ya, yb)), round(h - min(ya, yb))
    rs = slice(max(r0, box[0].start), min(r1, box[0].stop))  # inside the canvas and the axes
    cs = slice(max(c0, box[1].start), min(c1, box[1].stop))
    if rs.stop > rs.start and cs.stop > cs.start:
        if background.ndim == 2:  # the grey colour map over the image's range, as imshow's norm
            g = background.astype(np.float32)
            lo, hi = float(g.min()), float(g.max())
            scale = 255 / (hi - lo) if hi > lo else 0.0
            rgb = cv2.cvtColor(cv2.convertScaleAbs(g, alpha=scale, beta=-lo * scale),
                               cv2.COLOR_GRAY2RGB)
        elif background.dtype.kind == "f":
            rgb = cv2.convertScaleAbs(np.clip(background, 0, 1).astype(np.float32), alpha=255)
        else:
            # (clipped, as matplotlib draws integer RGB: 300 in a uint16 image wrapped to 44)
            rgb = np.clip(background, 0, 255).astype(np.uint8)
        shrink = (c1 - c0) * (r1 - r0) < rgb.shape[0] * rgb.shape[1]
        rgb = cv2.resize(rgb, (c1 - c0, r1 - r0),
                         interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)
        part = np.ascontiguousarray(rgb[rs.start - r0:rs.stop - r0, cs.start - c0:cs.stop - c0])
        alpha = float(image.get_alpha())
        out[rs, cs] = cv2.addWeighted(part, alpha, np.full_like(part, face), 1 - alpha, 0)
    # the drawing over it, a band of rows at a time (a few MB at most in floating point)
    for r in range(0, h, 64):
        t = top[r:r + 64].astype(np.float32)
        a = t[..., 3:] / 255
        band = out[r:r + 64]
        band[:] = np.clip(t[..., :3] * a + band * (1 - a) + 0.5, 0, 255)
    imsave(path, out, format="png", dpi=100)


def _bytes(colour: Any) -> np.ndarray:
    """A matplotlib colour's RGB as bytes."""
    from matplotlib.colors import to_rgb

    return np.round(np.array(to_rgb(colour)) * 255).astype(np.uint8)


class TrajectoryPlot:
    """A sink (:class:`~vistrack.io.tracks.Sink`) that collects every track's centres (a
    box's centre, or a point track's point; with their frames and identities, in arrays
    that double as they fill) and, when closed, plots them over the first frame
    (:func:`plot_trajectories`) to the PNG ``path``, titled
    ``"{name}: {tracks} tracks, {frames} frames"`` (without ``"{name}: "`` when it has no
    name).

    Parameters
    ----------
    path : str or Path
        The PNG to write.
    name : str
        The source's name, for the title.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from vistrack.types import Frame, Tracks
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "trajectories.png"
    >>> plot = TrajectoryPlot(path, "demo")
    >>> for k in range(1, 4):
    ...     box = np.array([[10.0 * k, 10, 10.0 * k + 20, 40]])
    ...     plot.write(Frame(k, 0.0, np.zeros((60, 80, 3), np.uint8)),
    ...                Tracks(ids=np.array([1]), boxes=box, points=None, scores=np.ones(1),
    ...                       classes=np.zeros(1)))
    >>> plot.close()
    >>> path.exists()
    True
    """

    def __init__(self, path: str | os.PathLike, name: str = ""):
        from ..io.tracks import _Column

        self.path, self.name = path, name
        # matplotlib now, before the frames: a broken installation fails before the run, and
        # its import (about 40 MB) is not taken at the end of an hour of video
        _import_agg()
        # what the figure needs of each row, in arrays that double as they fill: its frame,
        # identity and centre (32 bytes a row)
        self._frame_of, self._id_of, self._centres = _Column(), _Column(), _Column()
        self._first: np.ndarray | None = None
        self._frames = 0

    def write(self, frame: Frame, tracks: Tracks) -> None:
        """Keep the tracks' centres (and the first frame's image).

        Parameters
        ----------
        frame : Frame
            The frame; the first one's image is the background.
        tracks : Tracks
            Its tracks, boxes or points.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> from vistrack.types import Frame, Tracks
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "t.png"
        >>> plot = TrajectoryPlot(path, "one box")
        >>> for k in (1, 2):
        ...     box = np.array([[k, 0, 4, 4.0]])
        ...     plot.write(Frame(k, 0.0), Tracks(ids=np.array([1]), boxes=box, points=None,
        ...                                      scores=np.ones(1), classes=np.zeros(1)))
        >>> plot.close()
        >>> path.exists()
        True
        """
        if self._first is None:
            self._first = frame.image
        self._frames += 1
        if len(tracks):
            self._frame_of.add(np.full(len(tracks), int(frame.index)))
            self._id_of.add(np.asarray(tracks.ids).astype(int))
            self._centres.add(np.asarray(tracks.centers, dtype=float)[:, :2])

    def close(self) -> None:
        """Draw and save the figure.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> from vistrack.types import Frame, Tracks
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "t.png"
        >>> plot = TrajectoryPlot(path)
        >>> plot.write(Frame(1, 0.0), Tracks(ids=np.array([1]), boxes=np.array([[0, 0, 4, 4.0]]),
        ...                                  points=None, scores=np.ones(1), classes=np.zeros(1)))
        >>> plot.close()
        >>> path.exists()
        True
        """
        import cv2

        frames, ids = self._frame_of.view((0,)), self._id_of.view((0,))
        image = self._first
        if image is not None and image.ndim == 3:
            image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
        from ..io import replacing

        with replacing(self.path) as part:  # an earlier plot stays until this one is saved
            n, k = len(np.unique(ids)), self._frames
            counts = f"{n} track{'s' if n != 1 else ''}, {k} frame{'s' if k != 1 else ''}"
            plot_trajectories(frames, ids, self._centres.view((0, 2)), image, part,
                              title=f"{_label(self.name)}: {counts}" if self.name else counts)
