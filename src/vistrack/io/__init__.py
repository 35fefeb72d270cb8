"""Reading and writing outside formats: MOTChallenge files, video, and the sinks that write
tracks (:mod:`vistrack.io.tracks`). Every file is written whole or not at all
(:mod:`vistrack.io.atomic`)."""

from .atomic import PartialFile, open_replacing, partial_path, replacing
from .motchallenge import (
    MOT_CLASSES,
    MOTFormatError,
    MOTTable,
    SeqInfo,
    box_decimals,
    read_mot,
    read_seq_length,
    read_seqinfo,
    sequence_name,
    write_mot,
)
from .tracks import (
    BoxesWriter,
    CSVWriter,
    MOTWriter,
    PointsCSVWriter,
    Sink,
    TrackRows,
    write_boxes,
)
from .video import Frame, VideoError, VideoReader, VideoWriter

__all__ = ["MOT_CLASSES", "MOTFormatError", "MOTTable", "SeqInfo", "read_mot", "read_seqinfo",
           "read_seq_length", "sequence_name", "write_mot", "box_decimals", "Frame", "VideoError",
           "VideoReader", "VideoWriter",
           "Sink", "TrackRows", "MOTWriter", "CSVWriter", "PointsCSVWriter", "BoxesWriter",
           "write_boxes",
           "partial_path", "replacing", "open_replacing", "PartialFile"]
