"""Reading and writing outside formats: MOTChallenge files, video."""

from .motchallenge import (
    MOT_CLASSES,
    MOTFormatError,
    MOTTable,
    SeqInfo,
    read_mot,
    read_seqinfo,
    write_mot,
)
from .video import Frame, VideoError, VideoReader, VideoWriter

__all__ = ["MOT_CLASSES", "MOTFormatError", "MOTTable", "SeqInfo", "read_mot", "read_seqinfo",
           "write_mot", "Frame", "VideoError", "VideoReader", "VideoWriter"]
