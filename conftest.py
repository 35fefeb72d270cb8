"""Loaded by pytest for the tests in ``tests/`` and the examples in the docstrings of
``src/vistrack`` alike (both are collected from this folder)."""

import pytest


@pytest.fixture(autouse=True, scope="session")
def _temporary_files_in_pytests_folder(tmp_path_factory):
    """Temporary files of the tests, and of the processes they start, go to a folder in
    pytest's own (which keeps the last three runs' and removes older ones) instead of the
    system's: the docstrings' examples make their folders with ``tempfile.mkdtemp()``, as a
    user would, and leave them there. (Imported here, after ``tests/conftest.py`` has set
    numba's cache folder: it imports numba.)"""
    from vistrack._prebuilt_build import _own_temporary_folder

    with _own_temporary_folder(tmp_path_factory.getbasetemp(), "tempfile-"):
        yield
