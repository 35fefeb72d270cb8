r"""Feature tracking: Shi-Tomasi features, pyramidal Lucas-Kanade, and the seeds' checks.

One step (seed 003, "Tracking over many frames" and "Shi-Tomasi feature tracker"):

1. **update positions** with pyramidal Lucas-Kanade and a pure translation model (OpenCV's
   ``calcOpticalFlowPyrLK``);
2. **frame-to-frame check**: the patch at the new place must correlate with the previous
   frame's by at least ``min_ncc`` (Lucas-Kanade without enough pyramid can settle in a wrong
   minimum);
3. **large motions**: a feature Lucas-Kanade loses, or that fails the check, is searched for
   discretely, by normalised cross-correlation of its last patch over a window of
   ``search_radius`` pixels around its last place; the best integer location is refined to
   sub-pixel by Lucas-Kanade;
4. **forward-backward check**: tracked back to the previous frame, every feature must land
   within ``fb_max`` pixels of where it was (one the search found is searched for back the
   same way, around its new place in the previous frame, so that a look-alike the search
   matched does not come back to where the feature was);
5. **affine consistency**: the patch of the frame the feature was *first* seen in is
   registered to the current frame with an affine warp (inverse-compositional Lucas-Kanade,
   started from the last warp moved to the new position); a feature whose normalised RMS
   residual exceeds ``max_residual``, or whose warp has drifted from the translation-only
   position by more than ``fb_max``, is terminated. Comparing with the first frame, not the
   previous one, is what stops slow drift;
6. **start new features** (Shi-Tomasi's minimum eigenvalue of the second-moment matrix, away
   from the features kept) to keep ``max_features``, whenever a fifth of them are gone.

Identities are integers from 1, never reused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import as_finite, as_flag, as_uint8_image, as_whole
from ..types import Detections, Frame, Tracks
from ._affine import patch_ncc, prepare_templates, register
from .base import frame_image

__all__ = ["Features", "KLTTracker"]


@dataclass(frozen=True)
class Features:
    """The features of one frame: ``ids (N,)``, ``points (N, 2)`` (x, y), ``ages (N,)``
    (frames since each was started), ``residuals (N,)`` (of the affine check; 0 for new ones)
    and the number ``terminated`` in this frame.

    What :meth:`KLTTracker.track` returns; ``len()`` is the number of features.

    Attributes
    ----------
    ids : (N,) int64 ndarray
        Identities, integers from 1, never reused.
    points : (N, 2) ndarray
        Positions ``x, y`` in pixels.
    ages : (N,) int64 ndarray
        Frames since each feature was started (0 in its first frame).
    residuals : (N,) ndarray
        Normalised RMS residual of each feature's affine check in this frame (0 for new
        features, and without the check).
    terminated : int
        How many features were terminated in this frame.

    Examples
    --------
    >>> f = Features(np.array([1, 2]), np.array([[3.0, 4.0], [5.0, 6.0]]), np.zeros(2, int),
    ...              np.zeros(2), terminated=0)
    >>> len(f), f.detections().points.tolist()
    (2, [[3.0, 4.0], [5.0, 6.0]])
    """

    ids: np.ndarray
    points: np.ndarray
    ages: np.ndarray
    residuals: np.ndarray
    terminated: int

    def __len__(self) -> int:
        return int(self.ids.shape[0])

    def detections(self) -> Detections:
        """The features as point detections.

        Returns
        -------
        Detections
            ``points (N, 2)``, scores 1.

        Examples
        --------
        >>> f = Features(np.array([7]), np.array([[3.0, 4.0]]), np.zeros(1, int), np.zeros(1), 0)
        >>> d = f.detections()
        >>> d.points.tolist(), d.scores.tolist()
        ([[3.0, 4.0]], [1.0])
        """
        return Detections(points=self.points)


_LARGEST = 2**20
"""The largest of :class:`KLTTracker`'s sizes and counts, which OpenCV takes as C ints."""

_WINDOW = 4096
"""The largest window (``win_size``, ``block_size``) of :class:`KLTTracker`, in pixels."""


class KLTTracker:
    """Shi-Tomasi + Lucas-Kanade feature tracker with forward-backward and affine checks.

    Parameters
    ----------
    max_features : int
        Features to keep; new ones are started when fewer remain.
    quality, min_distance, block_size
        Shi-Tomasi: the smallest accepted minimum eigenvalue as a fraction of the best, the
        smallest distance between features, and the second-moment window.
    win_size, levels
        Lucas-Kanade window (pixels) and pyramid levels above the image.
    fb_max : float
        Largest forward-backward error, and largest disagreement of the affine position with
        the translation one (pixels).
    affine_check : bool
        Register each feature's first patch to the current frame (step 5 of the module), and
        terminate the features that fail.
    half : int
        Half-size of the patch compared with the first frame's ((2 half + 1)² pixels).
    max_residual : float
        Largest RMS difference of normalised intensities after affine registration
        (``√(2 (1 - NCC))``; 0.5 is a correlation of about 0.88).
    search_radius : int
        Discrete search window for features Lucas-Kanade loses; 0 turns it off.
    min_ncc : float
        Smallest correlation of a feature's patch with the previous frame's (a feature the
        discrete search found too, at its refined place); above -1, which a patch that
        leaves the image, or is flat, scores.

    Raises
    ------
    ValueError
        If a setting lies outside its range, named: ``max_features`` less than 1, a size or
        count past 2**20 (a window past 4096 pixels), which OpenCV cannot take.

    Examples
    --------
    A textured scene moving 2 pixels to the right:

    >>> import cv2
    >>> rng = np.random.default_rng(0)
    >>> scene = cv2.GaussianBlur(rng.integers(0, 256, (120, 160), dtype=np.uint8), (0, 0), 2)
    >>> klt = KLTTracker(max_features=50)
    >>> first = klt.track(scene)
    >>> second = klt.track(np.roll(scene, 2, axis=1))
    >>> kept = np.isin(first.ids, second.ids)
    >>> np.median(second.points - first.points[kept], axis=0).round(1) + 0.0
    array([2., 0.])
    """

    _prev32: np.ndarray  # float32 copy of the previous frame, set by track

    def __init__(self, max_features: int = 500, *, quality: float = 0.01,
                 min_distance: float = 7.0, block_size: int = 7, win_size: int = 15,
                 levels: int = 2, fb_max: float = 1.0, affine_check: bool = True,
                 half: int = 5, max_residual: float = 0.5, search_radius: int = 24,
                 min_ncc: float = 0.8):
        # each named where it is wrong (OpenCV's assertions named none; half=0 found no
        # feature and a NaN fb_max ended every one, without a word)
        self.max_features = as_whole(max_features, "max_features", 1)
        self.quality = as_finite(quality, "quality", 0.0, above=True, high=1.0)
        self.min_distance = as_finite(min_distance, "min_distance", 0.0)
        self.block_size = as_whole(block_size, "block_size", 1)
        self.win_size = as_whole(win_size, "win_size", 3)
        self.levels = as_whole(levels, "levels", 0)
        self.fb_max = as_finite(fb_max, "fb_max", 0.0, above=True)
        # ("False" was true; an array met numpy's "ambiguous")
        self.affine_check = as_flag(affine_check, "affine_check")
        self.half = as_whole(half, "half", 1)
        self.max_residual = as_finite(max_residual, "max_residual", 0.0, above=True)
        self.search_radius = as_whole(search_radius, "search_radius", 0)
        # (above -1: a patch that leaves its image, or is flat, scores -1, and at -1 such
        # features were kept)
        self.min_ncc = as_finite(min_ncc, "min_ncc", -1.0, above=True, high=1.0)
        # OpenCV takes them as C ints: min_distance 3e9 crashed the process in
        # goodFeaturesToTrack, the others failed in its words (an overload, naming none)
        for name in ("max_features", "min_distance", "levels", "half", "search_radius"):
            if getattr(self, name) > _LARGEST:
                raise ValueError(f"{name} must be at most 2**20 (pixels, or features: more "
                                 f"than any image holds); got {getattr(self, name):g}")
        # and allocates a window's square of each (win_size 100000: 40 GB, in its words)
        for name in ("block_size", "win_size"):
            if getattr(self, name) > _WINDOW:
                raise ValueError(f"{name} must be at most 4096 pixels (OpenCV allocates its "
                                 f"square for each window); got {getattr(self, name)}")
        self.reset()

    def reset(self) -> None:
        """Forget every feature; identities start again from 1.

        Examples
        --------
        >>> rng = np.random.default_rng(0)
        >>> klt = KLTTracker(max_features=20)
        >>> _ = klt.track(rng.integers(0, 256, (60, 80), dtype=np.uint8))
        >>> klt.reset()
        >>> len(klt.ids)
        0
        """
        self._prev: np.ndarray | None = None
        self.ids = np.zeros(0, np.int64)
        self.points = np.zeros((0, 2), np.float32)
        self.ages = np.zeros(0, np.int64)
        self.residuals = np.zeros(0)
        n = (2 * self.half + 1) ** 2
        self._T, self._SD = np.zeros((0, n)), np.zeros((0, n, 6))
        self._Hinv, self._p = np.zeros((0, 6, 6)), np.zeros((0, 6))
        self._next_id = 1

    def _lk(self, a, b, pts, guess=None):
        import cv2

        crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 0.03)
        flags = cv2.OPTFLOW_USE_INITIAL_FLOW if guess is not None else 0
        nxt, st, _ = cv2.calcOpticalFlowPyrLK(
            a, b, pts.reshape(-1, 1, 2), None if guess is None else guess.reshape(-1, 1, 2),
            winSize=(self.win_size, self.win_size), maxLevel=self.levels, criteria=crit,
            flags=flags)
        return nxt.reshape(-1, 2), st.ravel().astype(bool)

    def _forward_backward(self, grey, p0, p1, searched):
        # tracked back to the previous frame, a feature must land where it was. Lucas-Kanade
        # starts from the feature's new place; those the discrete search found moved too far
        # for it, and are searched for back the same way, around their new place in the
        # previous frame, Lucas-Kanade starting from what that finds. (Started from where
        # they were, they came back there whatever the search had matched: a feature hidden
        # in the new frame was taken to a look-alike 10-30 px off and kept)
        guess = p1.astype(np.float32)
        unfound = np.zeros(len(p1), bool)
        if searched.any():
            idx = np.flatnonzero(searched)
            back_at = self._search(grey, self._prev, p1[idx])
            lost = np.isnan(back_at[:, 0])
            guess[idx[~lost]] = back_at[~lost]
            unfound[idx[lost]] = True
        back, ok = self._lk(grey, self._prev, p1.astype(np.float32), guess=guess)
        return ok & ~unfound & (np.linalg.norm(back - p0, axis=1) <= self.fb_max)

    def _search(self, prev, cur, pts):
        # discrete NCC search of each feature's last patch around its last place
        import cv2

        h, r = self.half, self.search_radius
        H, W = cur.shape
        out = np.full((len(pts), 2), np.nan, np.float32)
        for k, (x, y) in enumerate(np.round(pts).astype(int)):
            if not (h <= x < W - h and h <= y < H - h):
                continue
            tpl = prev[y - h:y + h + 1, x - h:x + h + 1]
            x0, y0 = max(x - r - h, 0), max(y - r - h, 0)
            x1, y1 = min(x + r + h + 1, W), min(y + r + h + 1, H)
            win = cur[y0:y1, x0:x1]
            if win.shape[0] <= 2 * h or win.shape[1] <= 2 * h or tpl.std() < 1e-6:
                continue
            res = cv2.matchTemplate(win, tpl, cv2.TM_CCOEFF_NORMED)
            _, best, _, (bx, by) = cv2.minMaxLoc(res)
            if best > 0.7:
                out[k] = (x0 + bx + h, y0 + by + h)
        return out

    def _spawn(self, grey: np.ndarray) -> None:
        import cv2

        # top up when a fifth is gone (finding features costs a pass over the image)
        need = self.max_features - len(self.ids)
        if need <= 0 or (len(self.ids) and need < 0.2 * self.max_features):
            return
        # where a feature's patch, and the pixel around it that its gradients need, lie in
        # the image: corners nearer the border were asked for, then dropped, and the
        # features stayed short of max_features (483 of 500 on vtest.avi) until a fifth
        # was gone
        H, W = grey.shape
        m = self.half + 1
        mask = np.zeros(grey.shape, np.uint8)
        mask[m:max(H - m - 1, m), m:max(W - m - 1, m)] = 255
        for x, y in np.round(self.points).astype(int):
            cv2.circle(mask, (int(x), int(y)), int(self.min_distance), 0, -1)
        # `quality` is a share of the frame's strongest corner: OpenCV takes it of the
        # strongest the mask leaves, and each top-up, the features kept hidden, took
        # weaker corners (to 0.0057 of the frame's best for 0.01)
        eig = cv2.cornerMinEigenVal(grey, self.block_size)
        best, left = float(eig.max()), float(eig[mask > 0].max(initial=0.0))
        if left <= 0.0 or left < self.quality * best:
            return  # (no corner in the mask passes the frame's share)
        # twice the corners needed: some are dropped below, nearer a kept feature than
        # min_distance (the quota spent on them left the features short of max_features)
        new = cv2.goodFeaturesToTrack(grey, 2 * need, self.quality * best / left,
                                      self.min_distance, mask=mask, blockSize=self.block_size)
        if new is None:
            return
        pts = new.reshape(-1, 2).astype(np.float32)
        if len(self.points):
            # the mask's circles are drawn in whole pixels about rounded points, so a corner
            # could start up to 1.5 px nearer a kept feature than min_distance: measured
            from scipy.spatial import cKDTree

            near, _ = cKDTree(self.points).query(pts, distance_upper_bound=self.min_distance)
            pts = pts[near >= self.min_distance]
            if not len(pts):
                return
        pts = pts[:need]  # the strongest (OpenCV gives them strongest first)
        if self.affine_check:
            T, SD, Hinv, ok = prepare_templates(grey, pts, self.half)
            pts, T, SD, Hinv = pts[ok], T[ok], SD[ok], Hinv[ok]
        else:
            n = (2 * self.half + 1) ** 2
            T, SD, Hinv = np.zeros((len(pts), n)), np.zeros((len(pts), n, 6)), \
                np.zeros((len(pts), 6, 6))
        k = len(pts)
        p = np.zeros((k, 6))
        p[:, 4:] = pts
        self.ids = np.r_[self.ids, np.arange(self._next_id, self._next_id + k)]
        self._next_id += k
        self.points = np.r_[self.points, pts]
        self.ages = np.r_[self.ages, np.zeros(k, np.int64)]
        self.residuals = np.r_[self.residuals, np.zeros(k)]
        self._T, self._SD = np.r_[self._T, T], np.r_[self._SD, SD]
        self._Hinv, self._p = np.r_[self._Hinv, Hinv], np.r_[self._p, p]

    def step(self, frame: Frame, detections: Detections | None = None) -> Tracks:
        """Track one frame (:class:`~vistrack.tracking.Tracker`): the features as point
        tracks (score 1). ``frame`` carries the image; detections are not used (the tracker
        finds its own features). :meth:`track` gives the features' ages and residuals too.

        Parameters
        ----------
        frame : Frame
            The frame, with its image (grey or BGR uint8).
        detections : Detections, optional
            Not used.

        Returns
        -------
        Tracks
            The features kept and started in this frame: ``ids``, ``points (N, 2)``, scores 1
            and class 0.

        Raises
        ------
        TypeError
            If ``frame`` has no image.
        ValueError
            If the image's size differs from the previous frame's, or it is under
            ``2 half + 4`` pixels across or down, too small for any feature's patch.

        Examples
        --------
        >>> from vistrack.types import Frame
        >>> rng = np.random.default_rng(0)
        >>> image = rng.integers(0, 256, (60, 80), dtype=np.uint8)
        >>> tracks = KLTTracker(max_features=20).step(Frame(1, 0.0, image))
        >>> tracks.ids[:3].tolist(), tracks.points.shape[1], bool((tracks.scores == 1).all())
        ([1, 2, 3], 2, True)
        """
        f = self.track(frame_image(frame, "KLTTracker"))
        n = len(f)
        return Tracks(ids=f.ids, boxes=None, points=f.points, scores=np.ones(n),
                      classes=np.zeros(n, np.int64))

    def track(self, image: np.ndarray) -> Features:
        """Track the features into a new frame (grey or BGR uint8) and top them up.

        Parameters
        ----------
        image : (H, W) or (H, W, 3) ndarray
            The frame, grey or BGR uint8, of the previous frame's size.

        Returns
        -------
        Features
            The features kept and started, and how many were terminated.

        Raises
        ------
        ValueError
            If the image's size differs from the previous frame's, or it is under
            ``2 half + 4`` pixels across or down, too small for any feature's patch.

        Examples
        --------
        >>> import cv2
        >>> rng = np.random.default_rng(0)
        >>> scene = cv2.GaussianBlur(rng.integers(0, 256, (120, 160), dtype=np.uint8), (0, 0), 2)
        >>> klt = KLTTracker(max_features=50)
        >>> first = klt.track(scene)
        >>> second = klt.track(np.roll(scene, 2, axis=1))
        >>> int(first.ages.max()), int(second.ages.min()), second.terminated
        (0, 1, 0)
        """
        grey = as_uint8_image(image, grey=True)
        terminated = 0
        if min(grey.shape) < 2 * self.half + 4:
            # a feature's patch and the pixel around it that its gradients need: no frame
            # this small can hold one (none was found, frame after frame, without a word)
            raise ValueError(f"image is {grey.shape[1]}x{grey.shape[0]}: a feature's patch "
                             f"of half={self.half} and the pixel around it need "
                             f"{2 * self.half + 4} pixels across and down; give a smaller "
                             "half or a larger image")
        if self._prev is not None and grey.shape != self._prev.shape:
            # (whether or not the last frame left features to follow)
            raise ValueError(f"image is {grey.shape[1]}x{grey.shape[0]}; the previous "
                             f"frame was {self._prev.shape[1]}x{self._prev.shape[0]}")
        if self._prev is not None and len(self.ids):
            p0 = self.points.astype(np.float32)
            p1, ok = self._lk(self._prev, grey, p0)
            # the patch must still look like the last frame's
            g32 = grey.astype(np.float32)  # once, for the compiled checks
            ok &= patch_ncc(self._prev32, p0, g32, p1, self.half) >= self.min_ncc
            lost = ~ok
            searched = np.zeros(len(ok), bool)
            if self.search_radius > 0 and lost.any():
                found = self._search(self._prev, grey, p0[lost])
                good = ~np.isnan(found[:, 0])
                if good.any():
                    idx = np.flatnonzero(lost)[good]
                    ref, st = self._lk(self._prev, grey, p0[idx], guess=found[good])
                    # the refined place meets the frame-to-frame check too (the search's own
                    # bar, 0.7 at an integer place, kept features below min_ncc)
                    st &= patch_ncc(self._prev32, p0[idx], g32, ref, self.half) >= self.min_ncc
                    p1[idx[st]] = ref[st]
                    ok[idx[st]] = searched[idx[st]] = True
            # forward-backward, for every feature in one call
            cand = np.flatnonzero(ok)
            if len(cand):
                ok[cand] &= self._forward_backward(grey, p0[cand], p1[cand], searched[cand])
            H, W = grey.shape
            ok &= (p1[:, 0] >= 0) & (p1[:, 0] <= W - 1) & (p1[:, 1] >= 0) & (p1[:, 1] <= H - 1)
            if self.affine_check and ok.any():
                idx = np.flatnonzero(ok)
                p = self._p[idx].copy()
                p[:, 4:] = p1[idx]  # the last warp, moved to the new position
                rms = register(g32, self.half, self._T[idx], self._SD[idx], self._Hinv[idx],
                               p, iters=5, eps=0.03)
                drift = np.linalg.norm(p[:, 4:] - p1[idx], axis=1)
                good = (rms <= self.max_residual) & (drift <= self.fb_max)
                self._p[idx] = p
                self.residuals[idx] = rms
                ok[idx[~good]] = False
            terminated = int((~ok).sum())
            self.points = p1.astype(np.float32)
            self.ages = self.ages + 1
            keep = ok
            for name in ("ids", "points", "ages", "residuals", "_T", "_SD", "_Hinv", "_p"):
                setattr(self, name, getattr(self, name)[keep])
        # the caller's own array when it was grey uint8 already: copied, or drawing on the
        # frame after this call (to show the features) changed the next frame's reference
        self._prev = grey.copy() if np.shares_memory(grey, image) else grey
        self._prev32 = grey.astype(np.float32)
        self._spawn(grey)
        return Features(self.ids.copy(), self.points.astype(float), self.ages.copy(),
                        self.residuals.copy(), terminated)
