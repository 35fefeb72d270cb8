r"""Point trackers: positions (blob centres, particles, radar plots) with a linear-Gaussian model,
Mahalanobis gates, and association chosen by name.

One step: predict every track (``kf_predict``, batched); gate each measurement by its squared
Mahalanobis distance from each track's predicted measurement, :math:`d^2 \le \chi^2_m(p)`
(seed 003, "validation gate"); associate; correct; manage the lifecycle
(:mod:`vistrack.tracking.lifecycle`).

Association (``association=``):

- ``"gnn"``: global nearest neighbour on each pair's likelihood, :math:`d^2 + \ln |S|`
  against the :math:`\ln |S_1|` of a track one frame after an update
  (:math:`S_1 = H Q H^T + 2R` over one frame), the gate being the price of a track or a
  measurement left unassigned (the pairs of least total :math:`d^2 + \ln(|S| / |S_1|) -
  \chi^2`, not the most pairs): on :math:`d^2` alone a track missed for frames, its gate
  grown, was cheaper than one found in the frame before; then the gated pairs of the tracks
  and measurements left, on the same cost but each worth taking, so that a track however
  uncertain takes a measurement inside its gate that no other track wants; ``"nn"``: each
  track its nearest
  gated measurement; ``"greedy"``;
- ``"pda"``: each track corrected with all its gated measurements weighted by their
  probabilities (PDA), for clutter; ``"jpda"``: the probabilities computed jointly for tracks
  that share measurements (:mod:`vistrack.association.pda`);
- ``"ipda"``, ``"jipda"``: PDA and JPDA with each track's probability of existence (IPDA,
  JIPDA), which decides when a track is confirmed and deleted.

Every association works on the gated pairs, which a k-d tree finds, never on every track
against every measurement: the PDA family weighs and corrects a group of whole clusters
(tracks linked by shared measurements) at a time, each group a small dense problem, so
that thousands of points a frame cost about what ``gnn`` costs.

New tentative tracks start from the measurements no track took (``gnn``, ``nn``, ``greedy``) or
that are inside no track's gate (the PDA family), with zero velocity and ``init_speed`` as
its standard deviation.

Confirmation and deletion (:mod:`vistrack.tracking.lifecycle`): by counting, for all but IPDA
and JIPDA, ``confirm_hits`` updates in a row to confirm and ``max_lost`` seconds without one to
delete. In clutter, though, PDA and JPDA update a track whenever a measurement falls in its
gate, and one usually does: a track of clutter, or one left behind by a target that has
gone, is seldom missed and never deleted. IPDA and JIPDA (seed 003: "need to know when to
terminate a track") carry each track's probability of existence, the prior of a frame being
the last posterior times ``p_survive`` to the power of the time between (in seconds), and
the frame's evidence moving it (:func:`~vistrack.association.ipda_weights`): a new track
starts at ``init_existence``, is confirmed once its existence reaches
``confirm_existence``, and is deleted once it falls below ``delete_existence`` (or it has
not been updated for ``max_lost`` seconds); a tentative track is not deleted for a miss.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, cast

import numpy as np

from .._validate import as_finite, as_whole, is_real
from ..association import (
    chi2_threshold,
    gnn_sparse,
    ipda_weights,
    jipda_weights,
    jpda_weights,
    pda_weights,
)
from ..association.assign import _pair_components, greedy_pairs, nearest_pairs
from ..association.costs import cholesky_innovations, mahalanobis_pairs
from ..association.pda import _check as _check_pda
from ..association.pda import check_pair_likelihoods
from ..filters import kf_predict, kf_update, pda_update
from ..models import ConstantVelocity, Position
from ..types import Detections, Frame, Gaussian, Tracks
from .base import FixedSettings, frame_index
from .lifecycle import CONFIRMED, TENTATIVE, TrackTable

if TYPE_CHECKING:
    from ..models.protocols import MeasurementModel, MotionModel

__all__ = ["PointTracker", "POINT_ASSOCIATIONS"]

POINT_ASSOCIATIONS = ("gnn", "nn", "greedy", "pda", "jpda", "ipda", "jipda")
"""Association methods of :class:`PointTracker`."""

_EXISTENCE = ("ipda", "jipda")

_MOST_EXISTENCE = 1.0 - 2.0 ** -40
"""The largest prior existence a frame of IPDA or JIPDA takes (odds of about 1.1e12): at 1
(rounded from a track seen for some frames with ``p_survive`` 1) no miss lowers it."""


_GROUP_SIZE = 1 << 16
"""The entries (tracks x detections) of a group of clusters that :func:`_cluster_groups`
fills before it starts the next: a few hundred isolated tracks a group."""


def _cluster_groups(r: np.ndarray, c: np.ndarray, K: int, size: int = _GROUP_SIZE):
    """The gated pairs ``(r, c)`` of ``K`` tracks, grouped by whole clusters (connected
    components: tracks that share no detection, even through others, are in different
    clusters), clusters joined into a group while its tracks times its detections stay
    within ``size`` (a larger cluster is a group of its own). Yields, per group, its tracks
    and detections (sorted), the indices of its pairs in ``r``, and those pairs' rows and
    columns in the group's ``(tracks, detections)`` block.

    >>> groups = list(_cluster_groups(np.array([0, 1, 2]), np.array([5, 5, 7]), 3, size=1))
    >>> [(rows.tolist(), cols.tolist()) for rows, cols, *_ in groups]
    [([0, 1], [5]), ([2], [7])]
    """
    if not len(r):
        return
    root = _pair_components(r.astype(np.int64), c.astype(np.int64), K)  # a cluster's least track
    track_root = np.full(K, -1)
    track_root[r] = root
    det_root = np.full(int(c.max()) + 1, -1)
    det_root[c] = root
    roots = np.unique(root)
    tracks = np.bincount(np.searchsorted(roots, track_root[track_root >= 0]), minlength=len(roots))
    dets = np.bincount(np.searchsorted(roots, det_root[det_root >= 0]), minlength=len(roots))
    group = np.empty(len(roots), np.int64)
    g = nt = nd = 0
    for k, (a, b) in enumerate(zip(tracks.tolist(), dets.tolist())):
        if nt and (nt + a) * (nd + b) > size:
            g, nt, nd = g + 1, 0, 0
        group[k] = g
        nt, nd = nt + a, nd + b
    of_pair = group[np.searchsorted(roots, root)]
    order = np.argsort(of_pair, kind="stable")
    bounds = np.searchsorted(of_pair[order], np.arange(g + 2))
    for k in range(g + 1):
        sel = order[bounds[k]:bounds[k + 1]]
        rows, cols = np.unique(r[sel]), np.unique(c[sel])
        yield rows, cols, sel, np.searchsorted(rows, r[sel]), np.searchsorted(cols, c[sel])


def _log_determinants(S: np.ndarray) -> np.ndarray:
    """``ln |S_k|`` of innovation covariances ``S (K, m, m)``, from their Cholesky factors:
    GNN's likelihood cost and the PDA family's likelihoods both take it."""
    L = cholesky_innovations(S)
    return 2 * np.log(np.diagonal(L, axis1=1, axis2=2)).sum(1)



_FARTHEST = 1e150
"""The largest coordinate :meth:`PointTracker.step` takes: squared distances between points
within it are finite."""

class PointTracker(FixedSettings):
    """A multi-target point tracker (see the module).

    Parameters
    ----------
    association : str
        A name in :data:`POINT_ASSOCIATIONS`.
    motion, measurement
        Linear models: ``F(dt)``, ``Q(dt)`` and ``H(n)``, ``R()``. Default: constant velocity
        in 2-D with ``q = 1`` and position measurements with ``r = 1``.
    p_detect, clutter_density : float
        Detection probability and clutter per unit area (the PDA family).
    p_gate : float
        Gate probability ``p``: measurements beyond the ``p`` quantile of chi-square are not
        associated.
    init_speed : float
        Standard deviation of a new track's velocity, per axis (of each state component its
        first measurement does not determine). A new track starts at ``pinv(H) z``: the
        measured position, for ``H = [I 0]``.
    confirm_hits, max_lost, frame_rate
        As for :class:`~vistrack.tracking.BoxTracker` (``confirm_hits`` is not used by IPDA and
        JIPDA).
    p_survive : float
        IPDA and JIPDA: probability that a target is still there one second later, in
        (0, 1]. A frame's prior existence is at most 1 − 2⁻⁴⁰ (odds of about 10¹²), which
        binds only where ``p_survive`` a frame is within 1e-12 of 1 (1 itself): an
        existence rounded to 1 would be one no miss could lower.
    init_existence, confirm_existence, delete_existence : float
        IPDA and JIPDA: a new track's probability of existence, the existence that confirms
        a track, and the existence below which a track is deleted; ``0 <= delete_existence
        < init_existence < 1`` and ``delete_existence < confirm_existence <= 1``.
    max_distance : float, optional
        The farthest a link reaches, in the measurement's units: a measurement farther than
        this from a track's predicted measurement is not associated with it, however far the
        track's gate has grown while it was missed (trackpy's ``search_range``, measured
        there from the particle's last position, or from a predictor's). Reported
        measurements (``report="measurement"``) can lie a little farther than this from the
        track's last one, where the prediction has moved on from it. Default: the gate
        alone.
    report : {"estimate", "measurement"}
        What a track updated in a frame reports as its point: the filter's estimate (the
        default), or the measurement it was updated with (``"nn"``, ``"gnn"`` and
        ``"greedy"``, which give each track one), as trackpy's ``link`` keeps the located
        positions: a filtered position is drawn towards the track's past, which shrinks
        every step (a mean squared displacement taken from it came out low).

    Attributes
    ----------
    tracks : TrackTable
        Every track, tentative, confirmed or lost (:mod:`vistrack.tracking.lifecycle`).
    existence : (K,) ndarray
        Each track's probability of existence after the last frame (IPDA and JIPDA; 1 for
        the other associations).

    Raises
    ------
    ValueError
        If ``association`` is not in :data:`POINT_ASSOCIATIONS`, ``frame_rate``,
        ``max_lost``, ``init_speed`` or ``max_distance`` is not a finite number in its range,
        ``confirm_hits`` not a whole number >= 1, ``p_gate`` not in (0, 1), an existence
        setting is out of its range, ``init_speed`` is 1e154 or more (its square a variance),
        ``frame_rate`` so low that a frame's process noise is not finite, or a
        :class:`~vistrack.models.Position` measures more coordinates than the motion has
        (its third read the first velocity).
    TypeError
        If a probability, the clutter density or an existence setting is no number (a
        string).

    Examples
    --------
    >>> tr = PointTracker("gnn", frame_rate=1.0)
    >>> for f in range(1, 5):
    ...     out = tr.step(f, Detections(points=[[2.0 * f, 0.0], [50.0, 3.0 * f]]))
    >>> out.ids.tolist(), out.points.round(1).tolist()
    ([1, 2], [[8.0, 0.0], [50.0, 12.0]])
    """

    _fixed = frozenset({
        "association", "report", "motion", "measurement", "H", "R", "m", "p_detect",
        "clutter_density", "p_gate", "threshold", "init_speed", "confirm_hits", "max_lost",
        "frame_rate", "max_distance", "p_survive", "init_existence", "confirm_existence",
        "delete_existence"})

    def __init__(self, association: str = "gnn", *, motion: MotionModel | None = None,
                 measurement: MeasurementModel | None = None,
                 p_detect: float = 0.9, clutter_density: float = 1e-4, p_gate: float = 0.99,
                 init_speed: float = 10.0, confirm_hits: int = 3, max_lost: float = 1.0,
                 frame_rate: float = 30.0, p_survive: float = 0.99,
                 init_existence: float = 0.2, confirm_existence: float = 0.95,
                 delete_existence: float = 0.01, max_distance: float | None = None,
                 report: str = "estimate"):
        if association not in POINT_ASSOCIATIONS:
            raise ValueError(f"association must be one of {list(POINT_ASSOCIATIONS)}; "
                             f"got {association!r}")
        self.association = association
        if report not in ("estimate", "measurement"):
            raise ValueError(f"report must be 'estimate' or 'measurement'; got {report!r}")
        if report == "measurement" and association in ("pda", "jpda", "ipda", "jipda"):
            raise ValueError(f"report='measurement' needs an association that gives each "
                             f"track one measurement (nn, gnn, greedy); {association!r} weighs "
                             "every measurement in the gate")
        self.report = report
        # (a string was float()-ed for p_detect, and a bare "'<' not supported" for the rest)
        for name, v in (("p_detect", p_detect), ("clutter_density", clutter_density),
                        ("p_gate", p_gate), ("p_survive", p_survive),
                        ("init_existence", init_existence),
                        ("confirm_existence", confirm_existence),
                        ("delete_existence", delete_existence)):
            if not is_real(v):
                raise TypeError(f"{name} must be a number; got {v!r}")
        self.motion = motion if motion is not None else ConstantVelocity(dim=2, q=1.0)
        self.measurement = measurement if measurement is not None else Position(dim=2, r=1.0)
        space = getattr(self.motion, "dim", None)
        if isinstance(self.measurement, Position) and space is not None \
                and self.measurement.ndim_meas > space:
            # (its third coordinate was read as the first velocity, and every frame started a
            # new track, without a word)
            raise ValueError(f"the measurement measures {self.measurement.ndim_meas} "
                             f"coordinates of a motion in {space}: {self.measurement!r} with "
                             f"{self.motion!r}")
        n = self.motion.ndim_state
        self.H = np.asarray(self.measurement.H(n), dtype=float)
        self.R = np.asarray(self.measurement.R(), dtype=float)
        self.m = self.H.shape[0]
        self.p_detect, self.clutter_density = float(p_detect), float(clutter_density)
        if not 0.0 < p_gate < 1.0:
            raise ValueError(f"p_gate must be in (0, 1); got {p_gate}")
        self.p_gate = float(p_gate)
        _check_pda(self.p_detect, self.clutter_density, self.p_gate)  # at once, any mode
        self.threshold = chi2_threshold(self.m, self.p_gate)  # (a 0-d array was named "p")
        self.init_speed = as_finite(init_speed, "init_speed", 0.0, above=True)
        if self.init_speed >= 1e154:
            # (its square, a variance, overflowed at the first step, after the frame was
            # counted: the frame could not be given again)
            raise ValueError(f"init_speed must be below 1e154, its square a finite variance; "
                             f"got {init_speed!r}")
        self.confirm_hits = as_whole(confirm_hits, "confirm_hits", 1)
        self.max_lost = as_finite(max_lost, "max_lost", 0.0, what="number of seconds")
        self.frame_rate = as_finite(frame_rate, "frame_rate", 0.0, above=True)
        self.max_distance = None if max_distance is None else as_finite(
            max_distance, "max_distance", 0.0, above=True)
        # GNN's reference innovation: a track's one frame after an update (twice the
        # measurement noise and a frame's process noise), whose likelihood at the gate's edge
        # is the price of a pair left unassigned
        try:  # (a model that names its own overflow: said here for the frame rate)
            with np.errstate(over="ignore", invalid="ignore"):
                S_ref = self.H @ np.asarray(self.motion.Q(1.0 / self.frame_rate), float) \
                    @ self.H.T + 2 * self.R
        except ValueError:
            S_ref = np.full((1, 1), np.nan)
        if not np.isfinite(S_ref).all():  # (NaN for GNN's price, and Q named at the 2nd step)
            raise ValueError(f"frame_rate {frame_rate!r} makes a frame's process noise not "
                             f"finite ({self.motion!r} over {1.0 / self.frame_rate:g} s)")
        self._logdet_ref = float(np.linalg.slogdet(S_ref)[1])
        span = self.max_lost + 1.0 / self.frame_rate
        if self.init_speed * span >= 1e154:
            # a track never found again is predicted for up to max_lost and a frame: its
            # position's variance, about (init_speed t)², overflowed there, after the frame
            # was counted, and every later frame failed on S until the track was deleted
            raise ValueError(f"init_speed times (max_lost + one frame) must be below 1e154 "
                             f"(past it a lost track's variance, its square, overflows before "
                             f"the track is deleted); got {init_speed!r} over {span:g} s")
        with np.errstate(over="ignore", invalid="ignore"):
            Q_span = np.asarray(self.motion.Q(span), float)
        if not np.isfinite(Q_span).all():  # (as init_speed: S not finite, frame after frame)
            raise ValueError(f"max_lost {max_lost!r} makes the process noise of a lost track "
                             f"not finite before it is deleted ({self.motion!r} over "
                             f"{span:g} s)")
        # a new track starts where its first measurement puts it: pinv(H) z (the measured
        # components, for the usual H = [I 0]); what H does not see, with init_speed
        self._Hp = np.linalg.pinv(self.H)
        self._plain = self.H.shape[1] >= self.m and np.array_equal(
            self.H, np.eye(self.m, self.H.shape[1]))
        if not 0.0 < p_survive <= 1.0:
            raise ValueError(f"p_survive must be in (0, 1]; got {p_survive}")
        if not 0.0 <= delete_existence < init_existence < 1.0:
            raise ValueError("the existence settings must have 0 <= delete_existence < "
                             f"init_existence < 1; got delete_existence {delete_existence}, "
                             f"init_existence {init_existence}")
        if not delete_existence < confirm_existence <= 1.0:
            raise ValueError("the existence settings must have delete_existence < "
                             f"confirm_existence <= 1; got delete_existence {delete_existence}, "
                             f"confirm_existence {confirm_existence}")
        self.p_survive = float(p_survive)
        self.init_existence = float(init_existence)
        self.confirm_existence = float(confirm_existence)
        self.delete_existence = float(delete_existence)
        self.tracks = TrackTable(n)
        self.reset()
        self._made = True  # the settings are fixed from here (FixedSettings)

    def reset(self) -> None:
        """Forget every track; identities start again from 1.

        Examples
        --------
        >>> tr = PointTracker(frame_rate=1.0)
        >>> _ = tr.step(1, Detections(points=[[0.0, 0.0], [9.0, 9.0]]))
        >>> tr.reset()
        >>> tr.step(1, Detections(points=[[9.0, 9.0]])).ids.tolist()
        [1]
        """
        self.tracks.reset()
        self.existence = np.zeros(0)
        self.frame: int | None = None
        self._origin = 0  # the frame before the first stepped: times count from it (BoxTracker's)

    def _initial(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n, m = self.tracks.n, self.m
        if self._plain:  # H = [I 0]: derivative-major states, the measured position first
            mean = np.zeros((len(z), n))
            mean[:, :m] = z
            cov = np.zeros((n, n))
            cov[:m, :m] = self.R
            cov[m:, m:] = self.init_speed ** 2 * np.eye(n - m)
        else:  # the state the measurement determines, and init_speed across what it does not
            Hp = self._Hp
            mean = z @ Hp.T
            null = np.eye(n) - Hp @ self.H
            cov = Hp @ self.R @ Hp.T + self.init_speed ** 2 * null @ null.T
        return mean, np.broadcast_to(cov, (len(z), n, n)).copy()

    def step(self, frame: Frame | int | None = None,
             detections: Detections | None = None) -> Tracks:
        """Track one frame of point detections (:class:`~vistrack.tracking.Tracker`).

        Parameters
        ----------
        frame : Frame or int, optional
            The frame, or its index (increasing; default the next one); the time since the
            last frame is the gap in indices over ``frame_rate``. The image is not used.
        detections : Detections
            The frame's detections, with ``points (N, d)`` (None: no detections).

        Returns
        -------
        Tracks
            The confirmed tracks updated in this frame, with ``points`` and their
            covariances (``covs (K, d, d)``, of the first ``d`` coordinates: two, or one
            for points on a line), and ``scores``: the score of the detection each was
            updated with (the PDA family, which weighs every detection in the gate: of
            the most probable one).

        Raises
        ------
        TypeError
            If ``detections`` are not :class:`~vistrack.types.Detections` with points.
        ValueError
            If the points do not have the measurement's size or lie beyond ±1e150, or the
            frame index does not increase.

        Examples
        --------
        Two objects, associated by JPDA (the tracks of the first frame start confirmed):

        >>> tr = PointTracker("jpda", frame_rate=10.0)
        >>> for f in range(1, 4):
        ...     out = tr.step(Frame(f, (f - 1) / 10), Detections(points=[[2.0 * f, 0.0],
        ...                                                         [50.0, 3.0 * f]]))
        >>> out.ids.tolist(), out.points.round(1).tolist(), out.covs.shape
        ([1, 2], [[5.3, 0.0], [50.0, 8.0]], (2, 2, 2))
        """
        if detections is None:
            detections = Detections(points=np.zeros((0, self.m)))
        if not isinstance(detections, Detections) or detections.points is None:
            raise TypeError("detections must be vistrack.Detections with points")
        Z = detections.points
        if Z.ndim != 2 or Z.shape[1] != self.m:
            # (none of 3 coordinates was taken with no track, and named as z after the frame
            # was counted with some)
            raise ValueError(f"points must have {self.m} coordinates; got shape {Z.shape}")
        far = np.abs(Z) > _FARTHEST
        if far.any():
            # (a point 1.3e154 from a track overflowed the gate's squared distance, in
            # scipy's words: "The value of p too large for this dataset")
            i = int(np.flatnonzero(far.any(axis=1))[0])
            raise ValueError(f"points must lie within ±1e150, where the gates' squared "
                             f"distances hold; points[{i}] = {Z[i].tolist()}")
        # all or nothing: a step that fails (a model giving a covariance that is not finite)
        # leaves the tracker as it was, the frame not counted and no track deleted
        t = self.tracks
        saved = (self.frame, self.existence,
                 {k: v.copy() if isinstance(v, np.ndarray) else v
                  for k, v in t.__dict__.items()})
        try:
            return self._step(frame, Z, detections)
        except BaseException:
            self.frame, self.existence = saved[0], saved[1]
            t.__dict__.clear()
            t.__dict__.update(saved[2])
            raise

    def _gnn(self, r: np.ndarray, c: np.ndarray, d2: np.ndarray, S: np.ndarray,
             shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        """The gated pairs ``(r, c)`` (squared distances ``d2``) that global nearest
        neighbour takes."""
        if not len(r):
            return r, c
        # one assignment per connected group, on each pair's likelihood against a track's
        # one frame after an update: d² alone made a track lost for frames, its gate grown,
        # cheaper than one found in the frame before
        logdet = _log_determinants(S)
        cost = d2 + (logdet[r] - self._logdet_ref)
        r1, c1 = gnn_sparse(r, c, cost, shape, limit=self.threshold)
        # then the gated pairs of the tracks and measurements left, on the same cost but each
        # of them worth taking: a track whose |S| exceeds |S₁| by e^χ² (a new one of large
        # init_speed, or one lost long) could take no measurement at all, even one on its
        # prediction with no rival, and a new track started beside it every frame
        free = ~np.isin(r, r1) & ~np.isin(c, c1)
        r2, c2 = r[free], c[free]
        if len(r2):
            r2, c2 = gnn_sparse(r2, c2, cost[free], shape,
                                limit=float(cost[free].max()) + self.threshold)
        return np.r_[r1, r2], np.r_[c1, c2]

    def _step(self, frame: Frame | int | None, Z: np.ndarray,
              detections: Detections) -> Tracks:
        scores, classes = detections.scores, detections.classes
        assert scores is not None and classes is not None  # set by Detections.__post_init__
        frame = frame_index(frame, self.frame)
        first = self.frame is None
        gap = 0 if self.frame is None else frame - self.frame
        dt = gap / self.frame_rate
        if first:
            self._origin = frame - 1
        self.frame = frame
        time = (frame - self._origin) / self.frame_rate
        t = self.tracks
        if gap > 1 and len(t):
            # frames not stepped: the tracks that stepping them (without detections) would have
            # deleted, lost longer than max_lost at the frame before, are deleted before they
            # can take a detection (as BoxTracker.step does)
            gone = t.stale((frame - 1 - self._origin) / self.frame_rate, self.max_lost)
            if gone.any():
                t.keep(~gone)
                self.existence = self.existence[~gone]
        K = len(t)
        updated = np.zeros(K, bool)
        in_gate = np.zeros(len(Z), bool)
        measured: dict[int, np.ndarray] = {}  # each track's measurement of this frame
        keep_z = self.report == "measurement"
        if K:
            g = Gaussian(t.mean, t.cov)
            if dt > 0:
                g = kf_predict(g, self.motion.F(dt), self.motion.Q(dt))
            zp = g.mean @ self.H.T
            S = self.H @ g.cov @ self.H.T + self.R
            mean, cov = g.mean.copy(), g.cov.copy()
            # gated pairs only (a k-d tree finds the candidates): thousands of points stay
            # cheap
            r, c, d2 = mahalanobis_pairs(zp, S, Z, self.threshold)
            keep = t.classes[r] == classes[c]
            if self.max_distance is not None:  # however far the gate has grown
                keep &= ((zp[r] - Z[c]) ** 2).sum(1) <= self.max_distance ** 2
            r, c, d2 = r[keep], c[keep], d2[keep]
            if self.association in ("gnn", "nn", "greedy"):
                # on the gated pairs alone (the dense matrices nn and greedy were given took a
                # gigabyte at 8,000 points a frame, and 8 s)
                if self.association == "gnn":
                    r, c = self._gnn(r, c, d2, S, (K, len(Z)))
                else:
                    order = np.lexsort((c, r))  # row-major, as the dense assigners list them
                    r, c, d2 = r[order], c[order], d2[order]
                    r, c = (nearest_pairs(r, c, d2) if self.association == "nn"
                            else greedy_pairs(r, c, d2, (K, len(Z))))
                if len(r):
                    upd = kf_update(g[r], Z[c], self.H, self.R)
                    mean[r], cov[r] = upd.mean, upd.cov
                    t.scores[r] = scores[c]
                    if keep_z:
                        measured.update(zip(t.ids[r].tolist(), Z[c]))
                updated[r] = True
                in_gate[c] = True  # every measurement not taken starts a track
            else:  # the PDA family: the Gaussian likelihoods of the gated pairs
                in_gate[c] = True
                logdet = _log_determinants(S)
                lik_rc = np.exp(-0.5 * d2 - 0.5 * logdet[r] - 0.5 * self.m * np.log(2 * np.pi))
                args = dict(p_detect=self.p_detect, clutter_density=self.clutter_density,
                            p_gate=self.p_gate)
                existence = self.association in _EXISTENCE
                # at most _MOST_EXISTENCE: an existence rounded to 1 is one no miss lowers
                # (with p_survive 1, a track seen for some frames was never deleted by it)
                prior = np.minimum(self.existence * self.p_survive ** dt, _MOST_EXISTENCE)
                # written group by group into a new array (step keeps the old one, to put
                # back if the frame fails; a caller's reference to it stays as it was)
                self.existence = self.existence.copy()
                # named by the frame's track and measurement, as the weights name them in
                # their block of a group
                check_pair_likelihoods(r, c, lik_rc)
                weigh = cast(Callable[..., tuple[np.ndarray, ...]], {
                    "pda": pda_weights, "jpda": jpda_weights, "ipda": ipda_weights,
                    "jipda": jipda_weights}[self.association])
                hit = np.zeros(K, bool)
                hit[r] = True
                # weighed and corrected a group of whole clusters at a time (tracks that share
                # no detection do not meet in the weights or the update), each a small dense
                # problem: the tracks by every detection took 8 s and 1.8 GB over three frames
                # of 8,000 points
                for rows, cols, sel, lr, lc in _cluster_groups(r, c, K, _GROUP_SIZE):
                    lik = np.zeros((len(rows), len(cols)))
                    gate = np.zeros((len(rows), len(cols)), bool)
                    lik[lr, lc], gate[lr, lc] = lik_rc[sel], True
                    if existence:
                        beta, beta0, self.existence[rows] = weigh(lik, gate, prior[rows],
                                                                  **args)
                    else:
                        beta, beta0 = weigh(lik, gate, **args)
                    upd = pda_update(g[rows], Z[cols], self.H, self.R, beta, beta0)
                    mean[rows], cov[rows] = upd.mean, upd.cov
                    # the score of each track's most probable detection (the start's stayed)
                    seen = beta.max(axis=1) > 0
                    t.scores[rows[seen]] = scores[cols][np.argmax(beta[seen], axis=1)]
                if existence and not hit.all():  # nothing in their gates: a miss each
                    lone = np.flatnonzero(~hit)
                    none = np.zeros((len(lone), 0))
                    self.existence[lone] = weigh(none, none.astype(bool), prior[lone],
                                                 **args)[2]
                updated = hit
            t.mean, t.cov = mean, cov
        if self.association in _EXISTENCE:
            t.advance(updated, time, confirm_hits=np.iinfo(np.int64).max)
            t.state[updated & (t.state == TENTATIVE)
                    & (self.existence >= self.confirm_existence)] = CONFIRMED
            dead = (self.existence < self.delete_existence) | t.ended(
                updated, time, self.max_lost, miss_ends_tentative=False)
            t.keep(~dead)
            self.existence = self.existence[~dead]
        else:
            self.existence = self.existence[t.manage(updated, time, self.confirm_hits,
                                                     self.max_lost)]
        new = np.flatnonzero(~in_gate)
        if len(new):
            mean, cov = self._initial(Z[new])
            if self.association in _EXISTENCE:  # confirmed by its existence alone
                start = self.init_existence
                confirmed = start >= self.confirm_existence
            else:  # confirmed at once in the first frame, or where one update confirms
                start, confirmed = 1.0, first or self.confirm_hits <= 1
            t.add(mean, cov, time, classes[new], scores[new], confirmed=confirmed)
            self.existence = np.concatenate([self.existence, np.full(len(new), start)])
            if keep_z:
                measured.update(zip(t.ids[-len(new):].tolist(), Z[new]))
        out = np.flatnonzero((t.state == CONFIRMED) & (t.last_time == time))
        H = self.H
        covs = H @ t.cov[out] @ H.T
        points = t.mean[out] @ H.T
        if keep_z and len(out):
            points = np.array([measured[i] for i in t.ids[out].tolist()], dtype=float)
        return Tracks(ids=t.ids[out], boxes=None, points=points,
                      scores=t.scores[out], classes=t.classes[out], covs=covs[:, :2, :2])
