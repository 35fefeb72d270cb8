"""The whole configuration of ``vistrack track`` with a box tracker, read from and written to
TOML.

::

    [tracker]          # vistrack.tracking.BoxTrackerConfig, from the preset `name`
    name = "bytetrack"
    scores = "calibrated"
    high = 0.6
    ...
    [motion]           # vistrack.models.BoxMotion (per-frame noise at its frame_rate)
    std_pos = 0.05
    ...
    [offline]          # the offline mode (vistrack track --offline)
    enabled = false
    max_gap = 1.0
    ...
    [derived]          # written by --print-config: what the run derived; ignored when read
    frame_rate = 30.0
    ...

``vistrack track VIDEO --tracker dcpf`` reads a ``[dcpf]`` table of its own instead, every
field of :class:`~vistrack.tracking.DCPFConfig` (:func:`read_dcpf_config`,
:func:`dcpf_toml`).

A file may hold any part: what it leaves out keeps the preset's value (``[tracker] name``,
default ``bytetrack``). :func:`read_config` rejects unknown tables and keys, and values of the
wrong kind, naming the file, the line and the key; :func:`config_toml` writes a configuration
(and the values a run derived) that :func:`read_config` reads back to the same configuration.
"""

from __future__ import annotations

import difflib
import math
import os
import re
import sys
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ._validate import decode_text
from .io.motchallenge import _text_lines
from .models.box import BoxMotion
from .tracking.box import TRACKERS, BoxTrackerConfig

if TYPE_CHECKING:
    from collections.abc import Callable

    from .tracking.dcpf import DCPFConfig

__all__ = ["OfflineConfig", "TrackConfig", "read_config", "read_config_file", "config_toml",
           "ConfigError", "read_dcpf_config", "dcpf_toml"]


class ConfigError(ValueError):
    """A configuration file that cannot be used; the message names the file, the line
    and the key (``FILE:LINE: [table] key ...``).

    A ``ValueError``; :func:`read_config` raises it.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "bad.toml"
    >>> _ = path.write_text('[tracker]\\nhigh = "x"\\n')
    >>> try:
    ...     read_config(path)
    ... except ConfigError as e:
    ...     print(pathlib.Path(str(e)).name)
    bad.toml:2: [tracker] high must be a number; got 'x'
    """


@dataclass(frozen=True)
class OfflineConfig:
    """Settings of the offline mode (:func:`vistrack.tracking.smooth`), in seconds where they
    are durations.

    Attributes
    ----------
    enabled : bool
        Smooth, fill, follow back and join when the sequence is over.
    max_gap : float
        The longest gap in a track that is filled (seconds); the gap between two tracks
        joined (``link_gap``) is filled whatever its length.
    min_track_score : float
        The lowest mean score of a track's detections that is kept (a calibrated confidence
        with ``scores = "calibrated"``).
    start_score : float
        The lowest score that starts a track in the offline mode's pass, where it is above
        the tracker's ``new_track`` (on the same scale): a track starts only at a detection
        confident enough, and is then followed back through the less confident detections
        before it (``extend_iou``), so that fewer tracks start from clutter.
    extend_iou : float
        Follow tracks back through the detections left over while one overlaps the backward
        prediction by this IoU (0: not at all).
    link_gap, link_iou, link_window : float
        Join tracks up to ``link_gap`` seconds apart whose boxes, carried across the gap by
        the velocities of their last and first ``link_window`` seconds of detections (as
        many detections as frames in ``link_window``: over a longer time where a track
        missed frames), overlap by ``link_iou`` on average (``link_gap`` 0: never;
        ``link_iou`` above 0).
    calibration_iou_min : float
        With calibrated scores, the loosest overlap at which the whole file's score
        calibration links detections from frame to frame: where the detector's most
        confident detections persist less than half the time at the tracker's
        ``calibration_iou`` (objects that move too far between frames for their boxes to
        overlap that much), the calibration is fitted again at overlaps 0.1 lower, down to
        this (:meth:`~vistrack.tracking.calibration.ScoreCalibration.from_frames`;
        ``calibration_iou`` or more: never). Online, the calibration links at
        ``calibration_iou``; the tracker's association is the same either way.

    Raises
    ------
    ValueError
        If ``enabled`` is not a bool, a number is not finite, a duration or IoU negative, or
        an IoU above 1 (``min_track_score`` and ``start_score`` may be any finite number: on
        raw scores, as the detector gives them; :class:`TrackConfig` keeps calibrated ones in
        [0, 1]).

    Examples
    --------
    >>> OfflineConfig(enabled=True, max_gap=0.5).max_gap
    0.5
    >>> OfflineConfig(max_gap=-1)
    Traceback (most recent call last):
    ...
    ValueError: max_gap must be a finite number >= 0; got -1
    """

    enabled: bool = False
    max_gap: float = 1.0
    min_track_score: float = 0.75
    start_score: float = 0.8
    extend_iou: float = 0.5
    link_gap: float = 2.0
    link_iou: float = 0.3
    link_window: float = 0.3
    calibration_iou_min: float = 0.1

    def __post_init__(self) -> None:
        # numpy's numbers and flags too (np.int64(2) and np.bool_(True) were refused as no
        # number and no flag, where BoxTrackerConfig takes them), each kept as Python's own
        if not isinstance(self.enabled, (bool, np.bool_)):
            raise ValueError(f"enabled must be true or false; got {self.enabled!r}")
        object.__setattr__(self, "enabled", bool(self.enabled))
        # the two scores may be any number on raw scores (a detector's logits run below 0;
        # TrackConfig checks them against [0, 1] where they are calibrated confidences)
        scores = ("min_track_score", "start_score")
        for f in fields(self)[1:]:
            v = getattr(self, f.name)
            low = -math.inf if f.name in scores else 0
            # (-inf passed low <= v for the scores: a start_score of -inf was taken)
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer,
                                                                     np.floating)) \
                    or not math.isfinite(v) or not low <= v:
                raise ValueError(f"{f.name} must be a finite number"
                                 f"{'' if f.name in scores else ' >= 0'}; got {v!r}")
            object.__setattr__(self, f.name, v if type(v) in (int, float) else (
                int(v) if isinstance(v, np.integer) else float(v)))
        from .models.box import MAX_SECONDS

        for name in ("max_gap", "link_gap", "link_window"):
            # seconds, counted in frames (frames()): 1e308 overflowed there, with a traceback
            if getattr(self, name) > MAX_SECONDS:
                raise ValueError(f"{name} must be a number of seconds from 0 to "
                                 f"{MAX_SECONDS:g}; got {getattr(self, name)!r}")
        for name in ("extend_iou", "link_iou"):
            if getattr(self, name) > 1:
                raise ValueError(f"{name} must be in [0, 1]; got {getattr(self, name)!r}")
        if self.link_iou == 0 and self.link_gap > 0:  # (any two tracks within link_gap
            # were joined, however far apart)
            raise ValueError("link_iou must be in (0, 1] (at 0 any two tracks within link_gap "
                             "would be joined, however far apart); got 0")
        if not 0 < self.calibration_iou_min <= 1:  # (at 0 every box would link to any)
            raise ValueError(f"calibration_iou_min must be in (0, 1]; got "
                             f"{self.calibration_iou_min!r}")

    def frames(self, frame_rate: float) -> dict[str, int]:
        """The durations :func:`vistrack.tracking.smooth` counts in frames, at ``frame_rate``
        frames a second: ``max_gap``, ``link_gap`` and ``link_window`` (at least 1), each to
        the nearest frame, a half up, as the box tracker's coasting rounds (a half was
        rounded to the even frame: ``link_window`` 0.3 s was 4 frames at 15 frames/s and 8
        at 25).

        Raises
        ------
        ValueError
            If ``frame_rate`` is not a finite number > 0.

        Examples
        --------
        >>> OfflineConfig().frames(30.0)
        {'max_gap': 30, 'link_gap': 60, 'link_window': 9}
        >>> OfflineConfig().frames(2.5)
        {'max_gap': 3, 'link_gap': 5, 'link_window': 1}
        """
        from ._validate import as_finite
        from .tracking.lifecycle import nearest_whole

        # (-30 gave negative frame counts, NaN and inf numpy's conversion errors)
        rate = as_finite(frame_rate, "frame_rate", 0.0, above=True)
        return {"max_gap": nearest_whole(self.max_gap * rate),
                "link_gap": nearest_whole(self.link_gap * rate),
                "link_window": max(1, nearest_whole(self.link_window * rate))}


_MOTION = ("std_pos", "std_vel", "std_meas", "init_pos", "init_vel", "frame_rate")


@dataclass(frozen=True)
class TrackConfig:
    """Everything ``vistrack track`` with a box tracker is set by: the preset's ``name``, the
    tracker's settings, the box motion (None: the front-end's default) and the offline
    mode's settings.

    Attributes
    ----------
    name : str
        The preset the settings start from (:data:`vistrack.tracking.TRACKERS`).
    tracker : BoxTrackerConfig
        The tracker's settings.
    motion : BoxMotion or None
        The box motion; None: the default :class:`~vistrack.models.BoxMotion`.
    offline : OfflineConfig
        The offline mode's settings.

    Raises
    ------
    ValueError
        If ``name`` is no preset's, or the scores are calibrated and
        ``offline.start_score`` or ``offline.min_track_score`` is outside [0, 1].
    TypeError
        If ``tracker``, ``offline`` or ``motion`` is not of its type (a dict of settings:
        :meth:`with_values` takes those).

    Examples
    --------
    >>> cfg = TrackConfig.preset("sort").with_values(tracker={"high": 0.5})
    >>> cfg.name, cfg.tracker.two_stage, cfg.tracker.high, cfg.motion, cfg.offline.enabled
    ('sort', False, 0.5, None, False)
    """

    name: str = "bytetrack"
    tracker: BoxTrackerConfig = field(default_factory=BoxTrackerConfig)
    motion: BoxMotion | None = None
    offline: OfflineConfig = field(default_factory=OfflineConfig)

    def __post_init__(self) -> None:
        # (a name of no preset was written by config_toml into a file read_config refuses;
        # a dict for tracker failed in config_toml as "'dict' object has no attribute")
        if self.name not in TRACKERS:
            raise ValueError(f"name must be one of {sorted(TRACKERS)}; got {self.name!r}")
        for name, kind in (("tracker", BoxTrackerConfig), ("offline", OfflineConfig),
                           ("motion", BoxMotion)):
            value = getattr(self, name)
            if not isinstance(value, kind) and not (name == "motion" and value is None):
                raise TypeError(f"{name} must be a {kind.__name__}"
                                f"{' or None' if name == 'motion' else ''}; got "
                                f"{type(value).__name__} {value!r}")
        # the offline start replaces the tracker's new_track, so it is on the same scale, and
        # a track's mean score too (above 1, every track was dropped: 0 boxes)
        for name in ("start_score", "min_track_score"):
            value = getattr(self.offline, name)
            if self.tracker.scores == "calibrated" and not 0 <= value <= 1:
                raise ValueError(f"{name} must be in [0, 1] (a calibrated confidence); got "
                                 f"{value!r}")

    @classmethod
    def preset(cls, name: str = "bytetrack") -> TrackConfig:
        """The configuration of a preset in :data:`vistrack.tracking.TRACKERS`.

        Parameters
        ----------
        name : str
            The preset's name.

        Returns
        -------
        TrackConfig
            The preset's tracker settings, no motion (the default) and the offline mode
            off.

        Raises
        ------
        ValueError
            If ``name`` is not a preset.

        Examples
        --------
        >>> cfg = TrackConfig.preset("bytetrack")
        >>> cfg.name, cfg.tracker.two_stage
        ('bytetrack', True)
        """
        if name not in TRACKERS:
            raise ValueError(f"tracker must be one of {sorted(TRACKERS)}; got {name!r}")
        return cls(name=name, tracker=TRACKERS[name])

    def with_motion(self) -> TrackConfig:
        """This configuration with its motion: the default :class:`~vistrack.models.BoxMotion`
        where it has none. A run of a sequence's detections uses it so, and reports it so
        (``--print-config``).

        Returns
        -------
        TrackConfig
            ``self`` when it has a motion, else a copy with the default one.

        Examples
        --------
        >>> cfg = TrackConfig.preset("bytetrack")
        >>> cfg.motion is None, cfg.with_motion().motion == BoxMotion()
        (True, True)
        """
        return self if self.motion is not None else replace(self, motion=BoxMotion())

    def with_values(self, tracker: dict | None = None, motion: dict | None = None,
                    offline: dict | None = None) -> TrackConfig:
        """A copy with some values changed (None values are left alone).

        Parameters
        ----------
        tracker : dict, optional
            Fields of :class:`~vistrack.tracking.BoxTrackerConfig`.
        motion : dict, optional
            Arguments of :class:`~vistrack.models.BoxMotion` (``std_pos``, ``std_vel``,
            ``std_meas``, ``init_pos``, ``init_vel``, ``frame_rate``); the others keep the
            current motion's values (or the default's).
        offline : dict, optional
            Fields of :class:`OfflineConfig`.

        Returns
        -------
        TrackConfig
            The new configuration.

        Raises
        ------
        ValueError
            If a value is invalid.
        TypeError
            If a key names no field.

        Examples
        --------
        >>> cfg = TrackConfig.preset("sort").with_values(
        ...     tracker={"high": 0.5, "low": None}, motion={"std_pos": 0.1},
        ...     offline={"enabled": True})
        >>> cfg.tracker.high, cfg.motion.std_pos, cfg.motion.init_pos, cfg.offline.enabled
        (0.5, 0.1, 2.0, True)
        """
        def keep(d: dict | None) -> dict:
            return {k: v for k, v in (d or {}).items() if v is not None}

        t, m, o = keep(tracker), keep(motion), keep(offline)
        mot = self.motion
        if m:
            base = {k: getattr(mot or BoxMotion(), k) for k in _MOTION}
            base["std_meas"] = tuple(float(x) for x in base["std_meas"])
            mot = BoxMotion(**{**base, **m})
        return replace(self, tracker=replace(self.tracker, **t) if t else self.tracker,
                       motion=mot, offline=replace(self.offline, **o) if o else self.offline)


def _toml_loads(text: str) -> dict:
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover - Python 3.10
        import tomli as tomllib
    return tomllib.loads(text)


def _kind(value: object, kind: str) -> bool:
    if kind == "bool":
        return isinstance(value, bool)
    if kind == "int":
        return isinstance(value, int) and not isinstance(value, bool)
    if kind == "float":
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if kind == "str":
        return isinstance(value, str)
    return True


# the integers a file may give: those numpy's int64 holds
_INT64 = (-(2 ** 63), 2 ** 63 - 1)

_KIND_WORDS = {"bool": "true or false", "int": "an integer", "float": "a number",
               "str": "a string"}

def _key_line(text: str, table: str, key: str | None = None) -> int | None:
    r"""The line (from 1) of a TOML file's ``text`` that sets ``key`` of ``[table]`` (with
    ``key`` None, the line where the table begins): under a ``[table]`` header, as a dotted
    key ``table.key`` or in an inline table ``table = {key = ...}``. None where no line reads
    so (a key written inside a string of several lines, say): the message then names the
    file alone.

    Examples
    --------
    >>> text = 'high = 1\n[tracker]\n"high" = 0.5  # the first stage\n[motion]\nstd_pos = 0\n'
    >>> _key_line(text, "tracker", "high"), _key_line(text, "motion"), _key_line(text, "offline")
    (3, 4, None)
    >>> _key_line('offline = {enabled = true, max_gap = -1}\n', "offline", "max_gap")
    1
    >>> _key_line('tracker.high = 2\n', "tracker", "high")
    1
    >>> _key_line("[derived]\nnote = '''\n[tracker]\nhigh = 1\n'''\n[tracker]\nhigh = 2\n",
    ...           "tracker", "high")
    7
    """
    def parts(dotted: str) -> list[str]:
        return [p.strip().strip("\"'") for p in dotted.split(".")]

    current: list[str] = []
    inside: str | None = None  # the delimiter of a string of several lines the line is in
    # (lines as editors and TOML count them: splitlines also broke at U+2028 in a comment)
    for number, line in enumerate(_text_lines(text), 1):
        if inside is not None:  # (a key's text in such a string was named as the key's line)
            if inside in line:
                inside = None
            continue
        # read with string methods, not patterns, so a long line costs its length once
        line = line.strip()
        if line.startswith("[["):  # an array of tables: none of ours, but named where asked
            name = line[2:].partition("]]")[0]
            if key is None and parts(name) == [table]:
                return number
            current = ["[["]
            continue
        if line.startswith("["):
            name, _, rest = line[1:].partition("]")
            if rest.strip()[:1] in ("", "#"):
                current = parts(name)
                if current == ([table] if key is None else [table, key]):
                    return number
            continue
        said, equals, value = line.partition("=")
        if not equals or "#" in said:
            continue
        # (a string of several lines opens the value; a delimiter in a comment after a
        # value opens nothing, and named no line after it)
        opened = [d for d in ('"""', "'''") if value.lstrip().startswith(d)
                  and value.count(d) % 2]
        if opened:  # the value's string goes on over the next lines
            inside = opened[0]
        where = current + parts(said)
        if where[:1] != [table]:
            continue
        if key is None or where[:2] == [table, key]:
            return number
        if where == [table] and re.search(
                rf"[{{,]\s*([\"']?){re.escape(key)}\1\s*=", value):
            return number
    return None


def _keys_said(message: str, keys: dict[str, Any]) -> tuple[str | None, list[str]]:
    """The key of ``keys`` a setting's error ``message`` is about (the one it opens with,
    else the first it names; None where it names none), and every key it names."""
    named = [k for k in keys if re.search(rf"\b{re.escape(str(k))}\b", message)]
    first = re.match(r"\w+", message)
    return (first[0] if first and first[0] in keys else (named[0] if named else None)), named


def _load_toml(path: Path) -> tuple[str, dict[str, Any], Callable[..., str]]:
    """A configuration file's text, its TOML, and ``at(table, key=None)``: the file and
    the line that sets ``key`` of ``[table]`` where one does, for messages; ConfigError
    for a file that is no UTF-8 TOML."""
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise FileNotFoundError(f"{path} does not exist (--config FILE)") from None
    except IsADirectoryError:
        raise ConfigError(f"{path} is not a text TOML file (it is a folder)") from None
    text = decode_text(raw, path, "TOML", ConfigError)
    try:
        data = _toml_loads(text)
    except ValueError as exc:  # tomllib.TOMLDecodeError: names the line and column
        raise ConfigError(f"{path}: not valid TOML: {exc}") from None
    except RecursionError:  # arrays or inline tables nested a thousand deep
        raise ConfigError(f"{path}: not valid TOML: nested too deep") from None

    def at(table: str, key: str | None = None) -> str:
        line = _key_line(text, table, key)
        return f"{path}:{line}" if line is not None else str(path)
    return text, data, at


def read_dcpf_config(path: str | os.PathLike) -> tuple[DCPFConfig, dict[str, Any]]:
    """The detector-confidence particle filter's settings from a file's ``[dcpf]`` table
    (``vistrack track VIDEO --tracker dcpf --config FILE``; what it leaves out keeps
    :class:`~vistrack.tracking.DCPFConfig`'s default), and its ``[derived]`` table (what
    the run that printed it derived; empty without one).

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file (as :func:`dcpf_toml` writes).

    Returns
    -------
    DCPFConfig, dict

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    ConfigError
        For a file that is not UTF-8 text or not TOML, a table other than ``[dcpf]`` and
        ``[derived]`` (a box tracker's ``[tracker]`` too), a key that is no setting, or a
        value of the wrong kind or out of range, naming the file, the line and the key.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "dcpf.toml"
    >>> _ = path.write_text('[dcpf]\\ninit_score = 0.6\\nn_particles = 200\\n')
    >>> cfg, derived = read_dcpf_config(path)
    >>> cfg.init_score, cfg.n_particles, cfg.beta, derived
    (0.6, 200, 1.0, {})
    """
    from .tracking.dcpf import DCPFConfig

    path = Path(path)
    _, data, at = _load_toml(path)
    for table in data:
        if table not in ("dcpf", "derived"):
            hint = ("; it is the box trackers' table (bytetrack, sort), and --tracker dcpf "
                    "reads [dcpf]" if table in ("tracker", "motion", "offline") else "")
            raise ConfigError(f"{at(table)}: unknown table or key {table!r}{hint} (tables: "
                              "[dcpf], [derived])")
        if not isinstance(data[table], dict):
            raise ConfigError(f"{at(table)}: {table} must be a table ([{table}])")
    kinds = {f.name: cast(str, f.type) for f in fields(DCPFConfig)}
    given = dict(data.get("dcpf", {}))
    for key, value in given.items():
        kind = kinds.get(key)
        if kind is None:
            close = difflib.get_close_matches(str(key), kinds, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ConfigError(f"{at('dcpf', key)}: [dcpf] has no key {key!r}{hint} (keys: "
                              f"{', '.join(sorted(kinds))})")
        if not _kind(value, kind):
            raise ConfigError(f"{at('dcpf', key)}: [dcpf] {key} must be {_KIND_WORDS[kind]}; "
                              f"got {value!r}")
    try:
        cfg = DCPFConfig(**given)
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"{at('dcpf', _keys_said(str(exc), given)[0])}: [dcpf] {exc}"
                          ) from None
    return cfg, dict(data.get("derived", {}))


def dcpf_toml(cfg: DCPFConfig, derived: dict | None = None) -> str:
    """The detector-confidence particle filter's settings as TOML, a ``[dcpf]`` table that
    :func:`read_dcpf_config` reads back to the same settings, with ``derived`` values in a
    last ``[derived]`` table that it ignores.

    Examples
    --------
    >>> from vistrack.tracking import DCPFConfig
    >>> text = dcpf_toml(DCPFConfig(init_score=0.6), {"frame_rate": 7.0})
    >>> text.splitlines()[2:4], "init_score = 0.6" in text, text.splitlines()[-1]
    (['[dcpf]', 'beta = 1.0'], True, 'frame_rate = 7.0')
    """
    kinds = {f.name: cast(str, f.type) for f in fields(cfg)}
    lines = ["# vistrack track configuration: vistrack track VIDEO --tracker dcpf --config "
             "FILE", "", "[dcpf]"]
    lines += [f"{k} = {_value(v, kinds[k])}" for k, v in asdict(cfg).items()]
    return "\n".join(lines + _derived_lines(derived)) + "\n"


def read_config(path: str | os.PathLike, base: TrackConfig | None = None) -> TrackConfig:
    """Read a configuration file (see the module) over ``base`` (default: the preset its
    ``[tracker] name`` gives, ``bytetrack`` without one).

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file.
    base : TrackConfig, optional
        What the file's values are put over. When the file names another preset, that
        preset's tracker settings are the base, with ``base``'s motion and offline settings.

    Returns
    -------
    TrackConfig
        The configuration (the ``[derived]`` table is ignored).

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    ConfigError
        For a file that is not UTF-8 text or not TOML, an unknown table or key, or a value
        of the wrong kind or out of range, naming the file, the line and the key.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "track.toml"
    >>> _ = path.write_text('[tracker]\\nname = "sort"\\nhigh = 0.5\\n'
    ...                     '[offline]\\nenabled = true\\n')
    >>> cfg = read_config(path)
    >>> cfg.name, cfg.tracker.high, cfg.offline.enabled
    ('sort', 0.5, True)
    """
    return read_config_file(path, base)[0]


def read_config_file(path: str | os.PathLike, base: TrackConfig | None = None
                     ) -> tuple[TrackConfig, dict[str, Any]]:
    """:func:`read_config`'s configuration and the file's ``[derived]`` table (empty
    without one), from one read of the file: what a run printed beside its configuration
    (``vistrack track --print-config``), which the command line compares with the run it
    is given to."""
    return _read_config_file(path, base)[:2]


def _read_config_file(path: str | os.PathLike, base: TrackConfig | None = None,
                      over: dict[str, dict[str, Any]] | None = None,
                      names: dict[tuple[str, str], str] | None = None
                      ) -> tuple[TrackConfig, dict[str, Any], dict[str, frozenset[str]]]:
    """:func:`read_config_file`, and the keys the file sets in each table (``tracker``,
    ``motion``, ``offline``): what it leaves to the preset, or to the command line's
    front-end (a background model's still camera).

    ``over`` holds values put over the file's, table by table (the command line's options,
    whose names ``names`` gives by table and key), checked with them: checked alone first,
    a file of raw thresholds (``high = 3``) was refused before ``--scores raw`` came over
    it, and one of ``high = 0.2`` before ``--low 0.1``. A value at fault that ``over``
    gave is named by its option."""
    path = Path(path)
    text, data, at = _load_toml(path)
    unknown = set(data) - {"tracker", "motion", "offline", "derived"}
    if unknown:
        first = sorted(unknown)[0]
        close = difflib.get_close_matches(str(first), ["tracker", "motion", "offline"], n=1)
        hint = (f"; did you mean [{close[0]}]?" if close else
                "; it is --tracker dcpf's table" if first == "dcpf" else "")
        raise ConfigError(f"{at(first)}: unknown table or key {first!r}{hint} (tables: "
                          "[tracker], [motion], [offline], [derived])")
    for table in ("tracker", "motion", "offline", "derived"):
        if table in data and not isinstance(data[table], dict):
            raise ConfigError(f"{at(table)}: {table} must be a table ([{table}])")
    tracker = dict(data.get("tracker", {}))
    name = tracker.pop("name", None)
    if name is not None and (not isinstance(name, str) or name not in TRACKERS):
        raise ConfigError(f"{at('tracker', 'name')}: [tracker] name must be one of "
                          f"{sorted(TRACKERS)}; got {name!r}")
    cfg = base if base is not None else TrackConfig.preset(name or "bytetrack")
    if name is not None and base is not None and name != base.name:
        cfg = replace(TrackConfig.preset(name), motion=base.motion, offline=base.offline)
    # both modules use postponed annotations: a field's type is its annotation's text
    kinds: dict[str, dict[str, str]] = {
        "tracker": {f.name: cast(str, f.type) for f in fields(BoxTrackerConfig)},
        "offline": {f.name: cast(str, f.type) for f in fields(OfflineConfig)},
        "motion": {"std_pos": "float", "std_vel": "float", "std_meas": "list",
                   "init_pos": "float", "init_vel": "float", "frame_rate": "float"}}
    values = {"tracker": tracker, "motion": dict(data.get("motion", {})),
              "offline": dict(data.get("offline", {}))}
    for table, given in values.items():
        for key, value in given.items():
            kind = kinds[table].get(key)
            if kind is None:
                # a key of another table, or a near spelling of one of this table's
                elsewhere = [t for t in kinds if key in kinds[t]]
                close = difflib.get_close_matches(str(key), kinds[table], n=1)
                hint = (f"; it is a key of [{elsewhere[0]}]" if elsewhere else
                        f"; did you mean {close[0]!r}?" if close else "")
                raise ConfigError(f"{at(table, key)}: [{table}] has no key {key!r}{hint} "
                                  f"(keys: {', '.join(sorted(kinds[table]))})")
            if kind == "list":
                ok = (isinstance(value, (int, float)) and not isinstance(value, bool)) or (
                    isinstance(value, list) and len(value) == 4
                    and all(_kind(v, "float") for v in value))
                if not ok:
                    raise ConfigError(f"{at(table, key)}: [{table}] {key} must be a number "
                                      f"or a list of 4 numbers; got {value!r}")
                given[key] = tuple(value) if isinstance(value, list) else value
            elif not _kind(value, kind):
                raise ConfigError(f"{at(table, key)}: [{table}] {key} must be "
                                  f"{_KIND_WORDS[kind]}; got {value!r}")
            elif kind == "int" and not _INT64[0] <= value <= _INT64[1]:
                # TOML allows it; numpy's int64 (the trackers' arrays) would overflow later
                raise ConfigError(f"{at(table, key)}: [{table}] {key} must be an integer from "
                                  f"{_INT64[0]} to {_INT64[1]}; got {value!r}")
            elif kind == "float":
                given[key] = float(value)
    for table, given in values.items():  # one table at a time, to name the one that is wrong
        extra = (over or {}).get(table, {})
        merged = {**given, **extra}
        try:
            cfg = cfg.with_values(**{table: merged})
        except ValueError as exc:
            key, named = _keys_said(str(exc), merged)
            # an option's value the message is about: the options, over the file where it
            # gave a value the message names too
            theirs = [k for k in extra if k == key or k in named] if key in extra or (
                key is None) else []
            if theirs:
                options = ", ".join((names or {}).get((table, k), f"[{table}] {k}")
                                    for k in theirs)
                where = "" if all(k in extra for k in named) else f" over {path}"
                raise ConfigError(f"{options}{where}: {exc}") from None
            # the file's value at fault, with what the options made of it (--scores
            # calibrated: a start_score of 3 the file gave for raw scores)
            given_options = [f"{n} {(over or {})[t][k]}" for (t, k), n in (names or {}).items()
                             if k in (over or {}).get(t, {})]
            with_ = f" (with {', '.join(given_options)})" if given_options else ""
            raise ConfigError(f"{at(table, key)}: [{table}] {exc}{with_}") from None
    keys = {t: frozenset(data.get(t, {})) for t in ("tracker", "motion", "offline")}
    return cfg, dict(data.get("derived", {})), keys


def _value(v: object, kind: str | None = None) -> str:
    """``v`` as a TOML value; numpy's scalars as Python's, and a whole float as an integer
    where the field's ``kind`` is ``"int"`` (which :func:`read_config` reads)."""
    if isinstance(v, np.generic):  # np.float64(0.5), np.False_: their repr is no TOML
        v = v.item()
    if kind == "int" and isinstance(v, float) and v.is_integer():
        v = int(v)
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):  # an inline table, its keys quoted (a class's "0", "2")
        return "{" + ", ".join(f"{_value(str(k))} = {_value(x)}" for k, x in v.items()) + "}"
    if isinstance(v, float):
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)  # round-trips exactly
    return str(v)


def _derived_lines(derived: dict | None) -> list[str]:
    """A last ``[derived]`` table of ``derived`` (none where it is empty or None), which the
    readers ignore."""
    if not derived:
        return []
    return ["", "[derived]  # what the run derived from the data; not read back"] + [
        f"{k} = {_value(v)}" for k, v in derived.items()]


def config_toml(cfg: TrackConfig, derived: dict | None = None) -> str:
    """The configuration as TOML (see the module), with ``derived`` values in a last
    ``[derived]`` table that :func:`read_config` ignores.

    Parameters
    ----------
    cfg : TrackConfig
        The configuration; its ``[motion]`` table is written only when it has a motion.
    derived : dict, optional
        Values a run derived (:func:`vistrack.pipeline.derived_values`).

    Returns
    -------
    str
        The TOML text; floats are written exactly, so :func:`read_config` gives back the
        same values.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> cfg = TrackConfig.preset("sort").with_values(motion={"std_pos": 0.1})
    >>> text = config_toml(cfg, {"frame_rate": 30.0})
    >>> text.splitlines()[2:4], "[derived]" in text
    (['[tracker]', 'name = "sort"'], True)
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "track.toml"
    >>> _ = path.write_text(text)
    >>> back = read_config(path)
    >>> back.tracker == cfg.tracker, back.motion.std_pos, back.offline == cfg.offline
    (True, 0.1, True)
    """
    lines = ["# vistrack track configuration: vistrack track ... --config FILE",
             "", "[tracker]", f"name = {_value(cfg.name)}"]
    kinds = {f.name: cast(str, f.type) for f in (*fields(BoxTrackerConfig),
                                                  *fields(OfflineConfig))}
    lines += [f"{k} = {_value(v, kinds[k])}" for k, v in asdict(cfg.tracker).items()]
    if cfg.motion is not None:
        lines += ["", "[motion]"]
        for k in _MOTION:
            v = getattr(cfg.motion, k)
            lines.append(f"{k} = {_value([float(x) for x in v] if k == 'std_meas' else v)}")
    lines += ["", "[offline]"] + [f"{k} = {_value(v, kinds[k])}"
                                  for k, v in asdict(cfg.offline).items()]
    return "\n".join(lines + _derived_lines(derived)) + "\n"
