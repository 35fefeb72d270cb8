"""Reading and writing outside formats: MOTChallenge files."""

from .motchallenge import (
    MOT_CLASSES,
    MOTFormatError,
    MOTTable,
    SeqInfo,
    read_mot,
    read_seqinfo,
    write_mot,
)

__all__ = ["MOT_CLASSES", "MOTFormatError", "MOTTable", "SeqInfo", "read_mot", "read_seqinfo",
           "write_mot"]
