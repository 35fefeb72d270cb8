"""Loaded by pytest for the tests in ``tests/`` and the examples in the docstrings of
``src/vistrack`` alike (both are collected from this folder)."""

import os
import tempfile

import pytest


@pytest.fixture(autouse=True, scope="session")
def _temporary_files_in_pytests_folder(tmp_path_factory):
    """Temporary files of the tests, and of the processes they start, go to a folder in
    pytest's own (which keeps the last three runs' and removes older ones) instead of the
    system's: the docstrings' examples make their folders with ``tempfile.mkdtemp()``, as a
    user would, and leave them there."""
    folder = str(tmp_path_factory.mktemp("tempfile", numbered=False))
    saved, saved_env = tempfile.tempdir, os.environ.get("TMPDIR")
    tempfile.tempdir = os.environ["TMPDIR"] = folder
    yield
    tempfile.tempdir = saved
    if saved_env is None:
        os.environ.pop("TMPDIR", None)
    else:
        os.environ["TMPDIR"] = saved_env
