r"""The detector-confidence particle filter of Breitenstein et al. (ICCV 2009, PAMI 2011; seed
004, "Tracking based on detector confidence"): one particle filter per target, observed
through the discrete detections, the detector's continuous confidence and a classifier of
that target learnt online.

**State and motion.** Each target has ``n_particles`` particles of ``(x, y, u, v)``: its box
centre and velocity in pixels a frame, moved by constant velocity with Gaussian noise
``(x, y) += k (u, v) + ε_xy``, ``(u, v) += ε_uv`` over the ``k`` frames since the last one
stepped; the noise scales with the target's height. ``sigma_pos`` and ``sigma_vel`` are its
standard deviations over one frame at ``noise_rate`` frames a second (PETS09's 7, where they
were chosen); at ``r = noise_rate / frame_rate`` they are those of the same random walks in
continuous time, ``ε_uv`` of variance ``k b``, ``b = r³ (sigma_vel h)²`` (the velocity in
pixels a frame), and ``ε_xy`` of variance ``k a``, ``a = r (sigma_pos h)²``, so that a target
moves as far in a second at any frame rate and its velocity spreads as far; its centre
nearly so (the velocity's noise moves it in whole frames: with the defaults its spread 1 s
after a start is 0.26 of its height at 7 frames/s and 0.28 at 30). Across a gap of
``k > 1`` frames ``ε_xy`` also carries how far each frame's velocity noise moved the centre
in the frames after it: variance ``b (k-1) k (2k-1) / 6`` more, and covariance
``b k (k-1) / 2`` with ``ε_uv``, so that a gap spreads the cloud as the frames stepped one
by one would. The box's size is
the target's, learnt from the detections associated with it.

**Association.** Detections are matched to targets greedily, best pair first, by the seed's
score ``S(tr, d) = g(tr, d) · (c_tr(d) + α · p(d))``: a gate ``g`` (the detection's centre
within ``gate_heights`` heights of the target's and its height within a factor 1.5), the
target's classifier at the detection (0.5, no preference, with the classifier off:
``eta`` 0), and how well the detection fits the particles' prediction. The seed's ``p(d)``
is the particles' density at the detection, ``Σ_p p_N(d - p) / N`` with a fixed kernel;
that falls as the cloud spreads while the target goes undetected, so a person missed for
about a second was not found again, whatever ``max_lost``.
Here ``p(d)`` is the predictive density of the detection's centre, a Gaussian of the
particles' mean and covariance plus the detection's noise (``sigma_det`` of the height), over
its value at the mean: 1 at the predicted place however uncertain it is. Pairs with ``S``
below ``min_score`` are not matched.

**Observation model**, each particle's weight (seed 004, slide "Observation model"):

    w = β · I(tr) · p_N(p - d*) + γ · d_c(p) · p_o(tr) + η · c_tr(p),

- ``I(tr) p_N(p - d*)``: if a detection ``d*`` was associated, a Gaussian of the particle's
  distance to it (standard deviation ``sigma_det`` of the height; unnormalised, 1 at ``d*``);
- ``d_c(p)``: the detector's confidence at the particle (a :class:`ConfidenceMap` at the
  target's height, its score squashed by a logistic). ``p_o(tr)`` says how much that
  confidence can be the target's own; here it is ``1 / (1 + k)`` with ``k`` the other targets
  whose boxes overlap this one's by more than 0.2 IoU (the confidence map cannot tell people
  apart where they overlap that much; boxes that touch at their edges do not share a
  person), which is our reading of the seed's term;
- ``c_tr(p)``: the target's own classifier at the particle's box: a logistic regression on
  the box's hue-saturation histogram, trained online by a few steps of gradient descent
  each frame, with the target's box as the positive and the other targets' boxes and
  background boxes around it as negatives (the paper uses online boosting; the seed's point
  is a light online classifier that tells nearby people apart).

The weights are normalised and the particles resampled every frame (systematic resampling,
as CONDENSATION). Setting ``beta``, ``gamma`` or ``eta`` to 0 removes a term: the seed's
ablation table compares Det, Det+DetConf, Det+Class and all three.

**Track management** is the shared lifecycle (:class:`~vistrack.tracking.TrackTable`), with
two rules of the seed's own. A detection that no target took, scoring at least
``init_score``, and overlapping no target's box by more than ``max_overlap`` IoU starts a
tentative target; one associated in ``confirm`` frames in a row is confirmed, and one missed
first is deleted. A confirmed target is *supported* in a frame (an update of the lifecycle)
when a detection is associated with it or, with the confidence term on, when the mean
confidence at its particles is at least ``min_confidence``; unsupported for longer than
``max_lost`` seconds, or with its centre out of the image, it ends. Of two confirmed targets
whose boxes overlap by more than ``merge_iou`` for more than ``merge_time`` seconds in a
row, the younger ends (two filters on one person). A target is reported in the frames where
it is supported. Times are frames over ``frame_rate``; the defaults (1.5 s and 0.5 s) are
10 and 3 frames at PETS09's 7 frames/s, where they were chosen. New targets start from the
strongest detections first, each overlapping neither a target nor a target started before
it in the frame by more than ``max_overlap``.
"""

from __future__ import annotations

import copy
import warnings
from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .._validate import as_number, as_rng, as_whole
from ..association import greedy, iou
from ..filters.particle import resample
from ..types import Detections, Frame, Tracks
from .base import FixedSettings, frame_image, frame_index
from .lifecycle import CONFIRMED, TENTATIVE, TrackTable

if TYPE_CHECKING:
    from collections.abc import Callable

    from ..frontends.detectors import ConfidenceMap

__all__ = ["DCPFConfig", "DetectorConfidencePF", "ColourFeatures"]


@dataclass(frozen=True)
class DCPFConfig:
    """Settings of :class:`DetectorConfidencePF` (see the module).

    Attributes
    ----------
    beta, gamma, eta : float
        Weights of the detection, detector-confidence and classifier terms (0 removes one).
    n_particles : int
        Particles per target.
    sigma_pos, sigma_vel : float
        Noise of the centre and the velocity over one frame at ``noise_rate`` frames a
        second, as fractions of the target's height (see the module for other rates).
    noise_rate : float
        The frame rate at which ``sigma_pos`` and ``sigma_vel`` are per frame.
    sigma_det : float
        Standard deviation of the detection term, as a fraction of the height.
    alpha : float
        Weight of the predictive density (see the module) in the association score. The
        score is at most ``1 + alpha`` (``0.5 + alpha`` with ``eta`` 0), so ``min_score``
        must lie below that.
    gate_heights : float
        A detection's centre must lie within this many heights of the target's.
    min_score : float
        The smallest association score that matches.
    init_score : float
        The smallest detection score that starts a target.
    max_overlap : float
        A new target must overlap no target by more IoU than this.
    merge_iou, merge_time : float
        Two confirmed targets overlapping by more IoU than ``merge_iou`` for more than
        ``merge_time`` seconds in a row: the younger ends.
    confirm : int
        Associations in a row that confirm a target.
    max_lost : float
        Seconds a confirmed target may go unsupported before it ends.
    min_confidence : float
        The mean confidence at its particles that supports a target without a detection.
    size_rate : float
        How fast the target's size follows its detections (exponential smoothing).
    learning_rate, epochs : float, int
        The classifier's gradient steps each frame.

    Raises
    ------
    TypeError
        If a setting is no number (a string, None, or a boolean where a real number is
        asked for).
    ValueError
        If a setting is NaN, ``beta``, ``gamma`` or ``eta`` is negative or infinite or all
        are 0, ``n_particles`` is not a whole number >= 2, ``confirm`` one >= 1 or
        ``epochs`` one >= 0 (a boolean there too), ``sigma_det``, ``noise_rate`` or
        ``gate_heights`` is not finite and > 0, ``sigma_pos``, ``sigma_vel``,
        ``learning_rate`` or ``alpha`` not finite and >= 0, ``size_rate``, ``max_overlap``,
        ``merge_iou`` or ``min_confidence`` not in [0, 1], ``min_score`` or ``init_score``
        not finite, ``min_score`` at or above the largest association score (no detection
        would ever be associated), or ``max_lost`` or ``merge_time`` negative (each error
        names the setting).

    Examples
    --------
    >>> DCPFConfig(eta=0.0).max_lost
    1.5
    """

    beta: float = 1.0
    gamma: float = 1.0
    eta: float = 0.3
    n_particles: int = 100
    sigma_pos: float = 0.04
    sigma_vel: float = 0.02
    noise_rate: float = 7.0
    sigma_det: float = 0.15
    alpha: float = 1.0
    gate_heights: float = 0.6
    min_score: float = 0.6
    init_score: float = 0.75
    max_overlap: float = 0.3
    merge_iou: float = 0.5
    merge_time: float = 0.5
    confirm: int = 2
    max_lost: float = 1.5
    min_confidence: float = 0.3
    size_rate: float = 0.3
    learning_rate: float = 5.0
    epochs: int = 10

    def __post_init__(self) -> None:
        def bad(name: str, must: str) -> ValueError:
            return ValueError(f"{name} must be {must}; got {getattr(self, name)}")

        whole = {"n_particles": 2, "confirm": 1, "epochs": 0}
        for f in fields(self):  # numbers, not NaN (a NaN sigma_pos was an IndexError later)
            v = getattr(self, f.name)
            if f.name in whole:  # 100.0 particles is 100 (frozen)
                object.__setattr__(self, f.name, as_whole(v, f.name, whole[f.name]))
                continue
            # a float (a TypeError naming the setting for a string, None or a boolean: True
            # was 1); a Decimal failed in isnan without naming it, a 0-d array stayed one
            object.__setattr__(self, f.name, as_number(v, f.name))
            if np.isnan(getattr(self, f.name)):
                raise bad(f.name, "a number (not NaN)")
        for name in ("beta", "gamma", "eta"):
            if getattr(self, name) < 0:
                raise bad(name, ">= 0")
            if getattr(self, name) == np.inf:  # inf / inf: NaN weights
                raise bad(name, "finite")
        if self.beta + self.gamma + self.eta <= 0:
            raise ValueError("at least one of beta, gamma and eta must be > 0")
        # sigma_det = 0 gave NaN detection terms (0 / 0 at the detection), and nothing was
        # ever associated
        if not 0 < self.sigma_det < np.inf:
            raise bad("sigma_det", "a finite number > 0")
        for name in ("sigma_pos", "sigma_vel", "learning_rate"):
            if not 0 <= getattr(self, name) < np.inf:
                raise bad(name, "a finite number >= 0")
        if not 0 <= self.size_rate <= 1:
            raise bad("size_rate", "in [0, 1] (the weight of a detection's size)")
        for name in ("max_lost", "merge_time"):
            if not getattr(self, name) >= 0:
                raise bad(name, ">= 0")
        if not 0 <= self.alpha < np.inf:  # a weight (inf made every score inf or NaN)
            raise bad("alpha", "a finite number >= 0")
        # each was taken whatever it was: merge_iou -1 ended two people who never met every
        # merge_time, gate_heights -1 started a new identity every frame and reported none
        for name in ("max_overlap", "merge_iou", "min_confidence"):
            if not 0 <= getattr(self, name) <= 1:
                raise bad(name, "in [0, 1]")
        if not 0 < self.gate_heights < np.inf:
            raise bad("gate_heights", "a finite number > 0 (box heights)")
        if not 0 < self.noise_rate < np.inf:
            raise bad("noise_rate", "a finite number > 0 (frames a second)")
        for name in ("min_score", "init_score"):  # (a detector's scores need not be in [0, 1])
            if not np.isfinite(getattr(self, name)):
                raise bad(name, "finite")
        # the classifier's term is below 1 (0.5 without it) and the predictive density at
        # most 1: alpha 0 with eta 0 took every detection as no target's, without a word
        top = (1.0 if self.eta > 0 else 0.5) + self.alpha
        # (the classifier's logistic stays below 1, and the density is 1 only at the predicted
        # place itself: the top is met by every detection only where it is the stand-in 0.5,
        # eta 0 and alpha 0 or too small to add to 0.5)
        if self.min_score > top or (self.min_score == top and (self.eta > 0 or top > 0.5)):
            raise ValueError(
                f"min_score must be below the largest association score, "
                f"{'1' if self.eta > 0 else '0.5 (the classifier off: eta 0)'} + alpha = "
                f"{top:g}; got {self.min_score} ("
                + ("no detection would ever be associated)" if self.min_score > top else
                   "only a detection exactly at a target's predicted centre would be "
                   "associated)"))


class ColourFeatures:
    """Hue-saturation histograms of any number of boxes of one frame, from per-bin integral
    images of the frame (each box's histogram is four lookups a bin).

    Parameters
    ----------
    image : (H, W, 3) uint8 ndarray
        The frame, BGR.
    bins, bins_s : int
        Hue and saturation bins (``dim = bins × bins_s`` features).
    scale : float
        The frame is resized by this before the histograms are counted.
    out : (dim, H', W') int32 ndarray, optional
        Where to write the integral images (``H'``, ``W'``: the resized frame's size plus
        one), to reuse one buffer frame after frame; used only if of that shape and type.

    Examples
    --------
    >>> im = np.zeros((40, 60, 3), np.uint8); im[:, 30:] = (0, 0, 255)  # right half red
    >>> f = ColourFeatures(im)
    >>> h = f(np.array([[0, 0, 20, 20], [40, 10, 20, 20]]))
    >>> h.shape, float(h[0] @ h[1])  # Bhattacharyya coefficient: black vs red
    ((2, 32), 0.0)
    """

    def __init__(self, image: np.ndarray, bins: int = 8, bins_s: int = 4, scale: float = 0.5,
                 out: np.ndarray | None = None):
        import cv2

        from .._validate import as_uint8_image

        im = as_uint8_image(image, channels=(3,))
        if im.ndim != 3:  # (a grey frame failed in OpenCV's words, naming nothing)
            raise ValueError(f"image must be a BGR frame (H, W, 3) for the colour features of "
                             f"the targets' classifiers; got a grey frame of shape {im.shape} "
                             "(with eta=0 there is no classifier)")
        small = cv2.resize(im, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
        hsv = cv2.cvtColor(small, cv2.COLOR_BGR2HSV)
        b = (hsv[..., 0].astype(np.int32) * bins // 180) * bins_s \
            + hsv[..., 1].astype(np.int32) * bins_s // 256
        # one integral image per bin, (bins, H + 1, W + 1), each written in place: a tracker
        # passes the same buffer every frame (a new 14 MB array a frame for 768 x 576, and a
        # second to stack the bins, made the C allocator map and fault in fresh pages)
        shape = (bins * bins_s, small.shape[0] + 1, small.shape[1] + 1)
        ok = (out is not None and out.shape == shape and out.dtype == np.int32
              and out.flags.c_contiguous)
        integral = out if out is not None and ok else np.empty(shape, np.int32)
        for k in range(shape[0]):
            cv2.integral((b == k).view(np.uint8), sum=integral[k])
        self.integral = integral
        self.scale = scale
        self.dim = bins * bins_s

    def __call__(self, xywh: np.ndarray) -> np.ndarray:
        """The features of boxes.

        Parameters
        ----------
        xywh : (..., 4) array_like
            Boxes ``x, y, w, h`` in image pixels.

        Returns
        -------
        (..., dim) ndarray
            The square roots of their normalised histograms (unit length: dot products are
            Bhattacharyya coefficients).
        """
        H, W = self.integral.shape[1] - 1, self.integral.shape[2] - 1
        b = np.asarray(xywh, float) * self.scale
        x0 = np.clip(np.round(b[..., 0]), 0, W).astype(int)
        y0 = np.clip(np.round(b[..., 1]), 0, H).astype(int)
        x1 = np.clip(np.round(b[..., 0] + b[..., 2]), 0, W).astype(int)
        y1 = np.clip(np.round(b[..., 1] + b[..., 3]), 0, H).astype(int)
        I = self.integral
        h = np.moveaxis(I[:, y1, x1] - I[:, y0, x1] - I[:, y1, x0] + I[:, y0, x0], 0, -1)
        return np.sqrt(np.maximum(h, 0) / np.maximum(h.sum(-1, keepdims=True), 1.0))


def _sigmoid(z: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-np.clip(z, -50, 50)))


_SHARED = frozenset({"confidence", "config", "rng", "_integral"})
"""What :meth:`DetectorConfidencePF.update` keeps by reference when it saves the tracker
to put back after a refused frame: the callable, the settings (replaced whole, never
changed in place), the generator (its state is saved) and the scratch buffer of the
integral images (written anew each frame)."""


class DetectorConfidencePF(FixedSettings):
    """Multi-person tracking by one particle filter per target (see the module).

    Parameters
    ----------
    config : DCPFConfig, optional
    confidence : callable, optional
        The detector's continuous confidence of an image, ``image -> ConfidenceMap``
        (:class:`~vistrack.frontends.detectors.HOGConfidence`, or your detector's), which
        :meth:`step` evaluates on each frame; needed when ``gamma > 0`` (the
        detector-confidence term).
    rng : int, numpy Generator or None
        The particles' randomness (default 0: the same tracks every run).
    frame_rate : float
        Frames per second, to turn frames into time (``max_lost``, ``merge_time``, and the
        motion's noise against ``noise_rate``).
    **overrides
        Fields of :class:`DCPFConfig`.

    Attributes
    ----------
    n_scored : int
        Detections seen with a score (not NaN) since the last :meth:`reset`.
    top_score : float
        The highest of their scores (``-inf`` before any): where it stays under
        ``init_score``, no target can start.

    Raises
    ------
    TypeError
        If ``config`` is not a :class:`DCPFConfig`, ``confidence`` is not callable, or
        ``rng`` is not an int seed, a numpy Generator or None (a boolean included).
    ValueError
        If ``rng`` is a negative seed, ``frame_rate`` is not a finite number > 0, or a
        setting is out of its range (as :class:`DCPFConfig` names it).

    Notes
    -----
    :meth:`step` is the tracker protocol (:class:`~vistrack.tracking.Tracker`): a frame with
    its BGR image, and its discrete detections, whose scores are taken on the detector's own
    scale (``init_score``'s default, 0.75, is for scores in (0, 1), as the confidence front
    end's peaks of HOG's squashed confidence). :meth:`update` is the same step with the
    confidence map given, for a map computed elsewhere.

    A target is of its first detection's class, takes detections of that class only, and
    is reported with it; two targets of different classes may overlap (a person by a car)
    without being merged, and a detection overlapping a target of another class starts one
    of its own.
    """

    _fixed = frozenset({"config", "frame_rate"})

    def __init__(self, config: DCPFConfig | None = None, *,
                 confidence: Callable[[np.ndarray], ConfidenceMap] | None = None,
                 rng: np.random.Generator | int | None = 0, frame_rate: float = 30.0,
                 **overrides: Any):
        if config is not None and not isinstance(config, DCPFConfig):
            # (a dict or a file's path failed in reset, "'dict' object has no attribute
            # 'n_particles'")
            raise TypeError(f"config must be a DCPFConfig (DCPFConfig(**settings), or "
                            f"vistrack.config.read_dcpf_config(path) for a file); got "
                            f"{type(config).__name__}")
        if config is None:
            config = DCPFConfig(**overrides)
        elif overrides:
            config = replace(config, **overrides)
        if confidence is not None and not callable(confidence):
            raise TypeError(f"confidence must be a callable image -> ConfidenceMap; got "
                            f"{type(confidence).__name__}")
        from .._validate import as_finite

        self.config = config
        self.confidence = confidence
        self.frame_rate = as_finite(frame_rate, "frame_rate", 0.0, above=True)
        self._rng_seed = rng
        self._integral: np.ndarray | None = None  # ColourFeatures' buffer, frame after frame
        self.reset()
        self._made = True  # the settings are fixed from here (FixedSettings)

    def reset(self) -> None:
        """Forget every target; identities start again from 1 (and, with an integer ``rng``,
        the default 0, the randomness starts again: the same frames give the same tracks;
        with None it is drawn afresh)."""
        config = self.config
        # (as_rng names a seed it cannot take: numpy's SeedSequence words before, and True
        # was the seed 1; reset is called when the tracker is made)
        self.rng = as_rng(self._rng_seed)
        N = config.n_particles
        # the lifecycle's table (mean: each target's box x, y, w, h), and per target its
        # particles, size, seconds in a row on an older target, and classifier
        self.tracks = TrackTable(4, cov_shape=(0,))
        self.particles = np.zeros((0, N, 4))
        self.size = np.zeros((0, 2))               # w, h
        self.overlapped = np.zeros(0)
        self.weights_clf = np.zeros((0, 0))
        self.frame = 0
        self._stepped = False  # (frame 0 stepped read as no frame: it could be stepped again)
        self._origin = 0  # the frame before the first stepped: times count from it (BoxTracker's)
        self._said_unsized = False
        # the detections' scores seen, against init_score (a run can say why nothing started)
        self.n_scored = 0
        self.top_score = -np.inf

    @property
    def _slow(self) -> float:
        """``noise_rate / frame_rate``: the motion noise's rate against this one's."""
        return self.config.noise_rate / self.frame_rate

    @property
    def ids(self) -> np.ndarray:
        """The identities of the targets held ``(T,)``."""
        return self.tracks.ids

    def step(self, frame: Frame, detections: Detections | None = None) -> Tracks:
        """Track one frame (:class:`~vistrack.tracking.Tracker`).

        Parameters
        ----------
        frame : Frame
            The frame, with its BGR image (the classifiers and the confidence read it).
        detections : Detections, optional
            The frame's detections (None: none). Their scores are taken on the detector's
            own scale: ``init_score`` and the defaults are for the confidence front end's,
            in (0, 1); :attr:`top_score` and :attr:`n_scored` hold the highest score seen
            and how many were.

        Returns
        -------
        Tracks
            The confirmed targets supported in this frame; scores are the mean detector
            confidence at their particles (1 without the confidence term).
        """
        image = frame_image(frame, "DetectorConfidencePF")
        # the frame's own index: a gap in the frames (images skipped as bad) is time, which
        # ends a target lost longer than max_lost (calls were counted: 13.9 s away, a target
        # kept its identity), and a frame before the last is refused, as by the box trackers
        # after the last frame stepped or updated (update() moves the frame too: checked
        # against step()'s alone, a frame before an update's was refused by the track
        # table, in seconds, after update() had taken its number)
        index = frame_index(frame, self.frame if self._stepped else None)
        if detections is None:
            detections = Detections(boxes=np.zeros((0, 4)))
        # (with gamma 0 nothing reads it: a dense HOG map a frame was computed for nothing)
        cmap = (self.confidence(image) if self.confidence is not None
                and self.config.gamma > 0 else None)
        if cmap is not None and not callable(getattr(cmap, "score", None)):
            # (an array was taken, and failed a frame later, in numpy's words)
            raise TypeError(f"confidence must be a callable image -> ConfidenceMap; it "
                            f"returned {type(cmap).__name__}")
        return self.update(image, detections, cmap, _index=index)

    # ------------------------------------------------------------------ helpers
    def _boxes(self, centres: np.ndarray, size: np.ndarray) -> np.ndarray:
        return np.concatenate([centres - size / 2, np.broadcast_to(size, centres.shape)], -1)

    def _classify(self, feats: np.ndarray, k: np.ndarray | slice) -> np.ndarray:
        W = self.weights_clf[k]
        return _sigmoid((feats * W[..., None, :-1]).sum(-1) + W[..., None, -1])

    def _train(self, feats: ColourFeatures, est: np.ndarray, train: np.ndarray) -> None:
        """A few gradient steps of each trained target's logistic regression: its box is the
        positive; the other targets' boxes and four boxes beside it the negatives."""
        cfg = self.config
        T = len(est)
        offsets = np.array([[-1.0, 0.0], [1.0, 0.0], [-0.5, -0.5], [0.5, 0.5]])
        for k in np.flatnonzero(train):
            c, s = est[k, :2] + est[k, 2:] / 2, est[k, 2:]
            neg = [est[j] for j in range(T) if j != k]
            neg += [np.r_[c + o * s - s / 2, s] for o in offsets]
            X = feats(np.vstack([est[k][None], np.array(neg)]))
            y = np.r_[1.0, np.zeros(len(neg))]
            sw = np.r_[len(neg), np.ones(len(neg))]       # balance the one positive
            Xb = np.c_[X, np.ones(len(X))]
            w = self.weights_clf[k]
            for _ in range(cfg.epochs):
                p = _sigmoid(Xb @ w)
                w -= cfg.learning_rate * (sw * (p - y)) @ Xb / sw.sum()
            self.weights_clf[k] = w

    # ------------------------------------------------------------------ one frame
    def update(self, image: np.ndarray, detections: Detections,
               confidence: ConfidenceMap | None = None, *, _index: int | None = None) -> Tracks:
        """One frame with its confidence map given: ``image`` (BGR), its ``detections`` and
        a :class:`~vistrack.frontends.detectors.ConfidenceMap` (None when ``gamma`` is 0);
        as :meth:`step`, the frame the one after the last.

        A frame refused, or stopped, partway (a grey image with ``eta`` > 0, a confidence
        map that gives NaN, Ctrl-C) leaves the tracker as it was before it, its random
        generator too: the frame can be given again. (The frame was taken, the particles
        moved and targets over a gap ended before such a refusal, and the same frame was
        then refused as one that does not increase.)"""
        if not isinstance(detections, Detections) or detections.boxes is None:
            # (point detections failed in Detections.xywh's words, after the frame moved)
            raise TypeError("detections must be vistrack.Detections with boxes")
        kept = {name: (value if name in _SHARED else copy.deepcopy(value))
                for name, value in vars(self).items()}
        drawn = self.rng.bit_generator.state
        try:
            return self._update(image, detections, confidence, _index)
        except BaseException:
            self.__dict__.update(kept)
            self.rng.bit_generator.state = drawn
            raise

    def _update(self, image: np.ndarray, detections: Detections,
                confidence: ConfidenceMap | None, _index: int | None) -> Tracks:
        cfg = self.config
        # refused before anything changes (the frame moved, and targets over a gap ended,
        # before this was refused)
        if cfg.gamma > 0 and confidence is None:
            raise ValueError("the detector-confidence term (gamma > 0) needs the detector's "
                             "confidence: construct with confidence=HOGConfidence() (or "
                             "your own), pass a ConfidenceMap to update(), or set gamma=0")
        if confidence is not None and not callable(getattr(confidence, "score", None)):
            # (an array was taken, and failed a frame later, in numpy's words)
            raise TypeError(f"confidence must be a ConfidenceMap; got "
                            f"{type(confidence).__name__}")
        # frames since the last one stepped (a gap of frames moves the targets as far)
        k = 1 if _index is None else max(1, _index - self.frame)
        self.frame = self.frame + 1 if _index is None else _index
        if not self._stepped:
            self._origin = self.frame - 1
        self._stepped = True
        time = (self.frame - self._origin) / self.frame_rate
        if k > 1 and len(self.ids):
            # frames left out (images skipped): the targets that stepping through them would
            # have ended, unsupported for longer than max_lost at the frame before this one,
            # end before they can take a detection (found in the frame after a gap of 1.8 s,
            # max_lost 1.5 s, a target kept its identity), as the box tracker's do
            gone = self.tracks.stale((self.frame - 1 - self._origin) / self.frame_rate,
                                     cfg.max_lost)
            if gone.any():
                self._select(~gone)
        img = np.asarray(image)
        H, W = img.shape[:2]
        feats = None
        if cfg.eta > 0:
            feats = ColourFeatures(img, out=self._integral)
            self._integral = feats.integral  # this frame's buffer, for the next
        T, N = len(self.ids), cfg.n_particles
        det_xywh = detections.xywh if len(detections) else np.zeros((0, 4))
        sized = (det_xywh[:, 2] > 0) & (det_xywh[:, 3] > 0)
        if not sized.all():
            # a box of no width or height is no target's: one of no height started a target
            # every frame (its height ratio 0/0), one of no width a track of no width
            if not self._said_unsized:
                warnings.warn(f"frame {self.frame}: {int((~sized).sum())} detection(s) of no "
                              "width or height left out (a box with no area can be no "
                              "target's); said once", RuntimeWarning, stacklevel=3)
                self._said_unsized = True
            detections = detections[sized]
            det_xywh = det_xywh[sized]
        det_c = det_xywh[:, :2] + det_xywh[:, 2:] / 2
        assert detections.classes is not None  # set by Detections.__post_init__
        det_cls = detections.classes if len(detections) else np.zeros(0, np.int64)
        # a target takes, starts from and is merged with its own class's only (a box of
        # class 7 took a target of class 3, reported as class 0)
        tab_cls = self.tracks.classes

        # predict: constant velocity over k frames, noise scaled by each target's height and,
        # as random walks in continuous time, by the frames' duration against noise_rate's
        h = self.size[:, 1:2, None]
        p = self.particles
        slow = self._slow
        z_pos = self.rng.standard_normal((T, N, 2))
        if k == 1:
            p[..., :2] += p[..., 2:] + z_pos * cfg.sigma_pos * h * np.sqrt(slow)
            p[..., 2:] += self.rng.standard_normal((T, N, 2)) * cfg.sigma_vel * h \
                * np.sqrt(slow ** 3)
        else:
            # k frames in one: the velocity's noise of each frame also moved the centre in
            # the frames after it, so the centre's noise has, beyond k of one frame's, the
            # variance b (k-1) k (2k-1) / 6 and the covariance b k (k-1) / 2 with the
            # velocity's (b one frame's velocity variance); drawn as that correlated pair
            z_vel = self.rng.standard_normal((T, N, 2))
            a = (cfg.sigma_pos * h) ** 2 * slow
            b = (cfg.sigma_vel * h) ** 2 * slow ** 3
            p[..., :2] += k * p[..., 2:] + z_pos * np.sqrt(k * a + b * k * (k * k - 1) / 12) \
                + z_vel * np.sqrt(b * k) * (k - 1) / 2
            p[..., 2:] += z_vel * np.sqrt(b * k)

        # associate greedily by S(tr, d) = g · (c_tr(d) + α · predictive density at d)
        match = np.full(T, -1)
        if T and len(det_c):
            centre = p[..., :2].mean(1)
            density = self._predictive(centre, p[..., :2], det_c)               # (T, D)
            dist = np.linalg.norm(det_c[None] - centre[:, None], axis=-1)
            ratio = det_xywh[None, :, 3] / self.size[:, None, 1]
            gate = ((dist <= cfg.gate_heights * self.size[:, None, 1]) & (ratio < 1.5)
                    & (ratio > 1 / 1.5) & (tab_cls[:, None] == det_cls[None, :]))
            if cfg.eta > 0:
                assert feats is not None  # made above when eta > 0
                clf = self._classify(feats(det_xywh)[None], slice(None))
            else:
                clf = np.full((T, len(det_c)), 0.5)
            S = np.where(gate, clf + cfg.alpha * density, -np.inf)
            r, c = greedy(-S, S >= cfg.min_score)  # best pair first
            match[r] = c

        # weigh: β I(tr) p_N(p - d*) + γ d_c(p) p_o(tr) + η c_tr(p)
        has = match >= 0
        conf_mean = np.zeros(T)
        if T:
            w = np.full((T, N), 1e-6)
            if cfg.beta > 0:
                if has.any():
                    sd = cfg.sigma_det * self.size[has, 1]
                    d2 = ((p[has, :, :2] - det_c[match[has]][:, None]) ** 2).sum(-1)
                    w[has] += cfg.beta * np.exp(-0.5 * d2 / sd[:, None] ** 2)
            if cfg.gamma > 0:
                # not None with gamma > 0: checked above
                dc = self._confidence(confidence, p, self.size)
                if not np.isfinite(dc).all():  # ("weights must be finite" in resample, before)
                    raise ValueError(f"frame {self.frame}: the confidence map "
                                     f"({type(confidence).__name__}) gave a score that is not a "
                                     "number at the particles of a target")
                conf_mean = dc.mean(1)
                boxes = self._boxes(p[..., :2].mean(1), self.size)
                xyxy = np.c_[boxes[:, :2], boxes[:, :2] + boxes[:, 2:]]
                ov = iou(xyxy, xyxy)
                np.fill_diagonal(ov, 0.0)
                p_o = 1.0 / (1.0 + (ov > 0.2).sum(1))  # (the module's 0.2 IoU)
                w += cfg.gamma * dc * p_o[:, None]
            if cfg.eta > 0:
                assert feats is not None  # made above when eta > 0
                pb = self._boxes(p[..., :2], self.size[:, None, :])
                w += cfg.eta * self._classify(feats(pb), slice(None))
            w /= w.sum(1, keepdims=True)
            est_c = (w[..., None] * p[..., :2]).sum(1)
            p[:] = np.take_along_axis(p, resample(w, "systematic", rng=self.rng)[..., None], axis=1)
        else:
            est_c = np.zeros((0, 2))

        # sizes from the associated detections
        if has.any():
            self.size[has] += cfg.size_rate * (det_xywh[match[has], 2:] - self.size[has])
        est = self._boxes(est_c, self.size)

        # support, then the lifecycle: a target is updated in the frames where it is supported
        tab = self.tracks
        confirmed = tab.state != TENTATIVE
        supported = has.copy()
        if cfg.gamma > 0:
            supported |= confirmed & (conf_mean >= cfg.min_confidence)
        tab.mean = est.copy()
        tab.advance(supported, time, cfg.confirm)
        confirmed = tab.state != TENTATIVE
        inside = (est_c[:, 0] >= 0) & (est_c[:, 0] < W) & (est_c[:, 1] >= 0) & (est_c[:, 1] < H)
        keep = ~tab.ended(supported, time, cfg.max_lost) & inside
        # two targets on one person: the younger ends once it has overlapped an older one
        # for merge_time seconds in a row (people crossing overlap for a few frames)
        covered = np.zeros(T, bool)
        if T > 1:
            xyxy = np.c_[est[:, :2], est[:, :2] + est[:, 2:]]
            ov = np.triu(iou(xyxy, xyxy), 1)       # rows are older: ids grow with the index
            both = (confirmed[:, None] & confirmed[None, :]
                    & (tab_cls[:, None] == tab_cls[None, :]))
            covered = cast(np.ndarray, ((ov > cfg.merge_iou) & both).any(0))  # (T,) array
        self.overlapped = np.where(covered, self.overlapped + k / self.frame_rate, 0.0)
        # for more than merge_time, whatever the rounding of the sum of the frames' 1 /
        # frame_rate (0.1 + 0.1 + 0.1 > 0.3 ended a target after 0.3 s at 10 frames/s), as
        # TrackTable.ended does for max_lost
        keep &= self.overlapped <= cfg.merge_time + 1e-9 * max(1.0, cfg.merge_time)
        report = (tab.state == CONFIRMED) & supported & keep
        out = Tracks(ids=tab.ids[report].copy(),
                     boxes=np.c_[est[report, :2], est[report, :2] + est[report, 2:]],
                     points=None, scores=conf_mean[report] if cfg.gamma > 0
                     else np.ones(int(report.sum())),
                     classes=tab.classes[report].copy())

        # the classifiers learn where their targets were detected
        if cfg.eta > 0 and has.any():
            assert feats is not None  # made above when eta > 0
            self._train(feats, est, has & keep)

        # end targets; start new ones from strong detections no target took
        self._select(keep)
        est = est[keep]
        if len(det_c):
            free = np.ones(len(det_c), bool)
            free[match[match >= 0]] = False
            assert detections.scores is not None  # set by Detections.__post_init__
            real = detections.scores[~np.isnan(detections.scores)]
            if len(real):
                self.n_scored += len(real)
                self.top_score = max(self.top_score, float(real.max()))
            strong = free & (detections.scores >= cfg.init_score)
            if strong.any():
                cand, cand_cls = det_xywh[strong], det_cls[strong]
                taken = self._starts(cand, detections.scores[strong], cand_cls, est,
                                     tab.classes)
                cand, cand_cls = cand[taken], cand_cls[taken]
                self._start(cand, cand_cls, feats, time)
                if cfg.confirm <= 1 and len(cand):
                    # confirmed as they start: reported in this frame too (they were not, so
                    # every track lost its first frame, and a target of one frame was never
                    # reported), at their detections' boxes, scored as the others
                    new_ids = self.ids[-len(cand):]
                    k = len(cand)
                    scores = (self._confidence(confidence, self.particles[-k:],
                                               self.size[-k:]).mean(1) if cfg.gamma > 0
                              else np.ones(k))
                    out = Tracks(ids=np.r_[out.ids, new_ids],
                                 boxes=np.r_[out.boxes, np.c_[cand[:, :2],
                                                              cand[:, :2] + cand[:, 2:]]],
                                 points=None, scores=np.r_[out.scores, scores],
                                 classes=np.r_[out.classes, cand_cls])
        return out

    def _starts(self, cand: np.ndarray, scores: np.ndarray, classes: np.ndarray,
                est: np.ndarray, est_classes: np.ndarray) -> np.ndarray:
        """Which candidate boxes ``cand (C, 4)`` (``x, y, w, h``) of ``classes`` start
        targets: taken by ``scores``, highest first, each overlapping no target's box ``est``
        of its class (``est_classes``) and no candidate of its class taken before it by more
        than ``max_overlap`` (two detections of one person, which a detection file may hold,
        started two targets, both reported until one ended)."""
        limit = self.config.max_overlap
        cxyxy = np.c_[cand[:, :2], cand[:, :2] + cand[:, 2:]]
        ok = np.ones(len(cand), bool)
        if len(est):
            exyxy = np.c_[est[:, :2], est[:, :2] + est[:, 2:]]
            ov = np.where(classes[:, None] == est_classes[None, :], iou(cxyxy, exyxy), 0.0)
            ok = ov.max(1) <= limit
        among = np.where(classes[:, None] == classes[None, :], iou(cxyxy, cxyxy), 0.0)
        taken = np.zeros(len(cand), bool)
        for j in np.argsort(-scores, kind="stable"):
            if ok[j] and not (among[j, taken] > limit).any():
                taken[j] = True
        return taken  # (in the detections' order, as before)

    def _predictive(self, centre: np.ndarray, xy: np.ndarray, det_c: np.ndarray) -> np.ndarray:
        """How well each detection's centre ``det_c (D, 2)`` fits each target's prediction
        ``(T, D)``: the predictive density of the detection, a Gaussian of the particles'
        mean ``centre (T, 2)`` and covariance (of ``xy (T, N, 2)``) plus the detection's
        noise (``sigma_det`` of the height), over its value at the mean (1 there)."""
        sd2 = (self.config.sigma_det * self.size[:, 1]) ** 2
        dev = xy - centre[:, None]
        S = np.einsum("tni,tnj->tij", dev, dev) / xy.shape[1] + sd2[:, None, None] * np.eye(2)
        e = det_c[None] - centre[:, None]                                      # (T, D, 2)
        m2 = np.einsum("tdi,tij,tdj->td", e, np.linalg.inv(S), e)
        return np.exp(-0.5 * m2)

    @staticmethod
    def _confidence(confidence: Any, p: np.ndarray, size: np.ndarray) -> np.ndarray:
        """The detector's confidence, squashed to (0, 1), at particles ``p (T, N, 4)`` of
        targets of sizes ``size (T, 2)``: ``(T, N)`` (its mean is a reported target's score)."""
        return _sigmoid(confidence.score(p[..., 0], p[..., 1], size[:, None, 1], outside=-10.0))

    def _select(self, keep: np.ndarray) -> None:
        self.tracks.keep(keep)
        for name in ("particles", "size", "overlapped", "weights_clf"):
            setattr(self, name, getattr(self, name)[keep])

    def _start(self, boxes: np.ndarray, classes: np.ndarray, feats: ColourFeatures | None,
               time: float) -> None:
        k, N = len(boxes), self.config.n_particles
        if k == 0:
            return
        c = boxes[:, :2] + boxes[:, 2:] / 2
        parts = np.zeros((k, N, 4))
        parts[..., :2] = c[:, None] + self.rng.standard_normal((k, N, 2)) \
            * self.config.sigma_pos * boxes[:, None, 3:4]
        # the velocity's spread in pixels a second as at noise_rate, in pixels a frame here
        parts[..., 2:] = self.rng.standard_normal((k, N, 2)) * self.config.sigma_vel \
            * boxes[:, None, 3:4] * self._slow
        dim = feats.dim + 1 if feats is not None else 1
        if self.weights_clf.shape[1] != dim:
            self.weights_clf = np.zeros((len(self.ids), dim))
        self.tracks.add(boxes, np.zeros((k, 0)), time, classes, np.zeros(k),
                        confirmed=self.config.confirm <= 1)
        self.particles = np.concatenate([self.particles, parts])
        self.size = np.concatenate([self.size, boxes[:, 2:]])
        self.overlapped = np.concatenate([self.overlapped, np.zeros(k)])
        self.weights_clf = np.concatenate([self.weights_clf, np.zeros((k, dim))])
        if feats is not None:
            # start each classifier on its first box
            est = self._boxes(self.particles[:, :, :2].mean(1), self.size)
            train = np.zeros(len(self.ids), bool)
            train[-k:] = True
            self._train(feats, est, train)
