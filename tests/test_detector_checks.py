"""What a detections file tells of its detector: its stride, the frames it did not deliver."""

import numpy as np
import pytest

from vistrack.detector_checks import detection_stride, undelivered_frames


def test_detection_stride_is_the_common_gap_between_the_frames_with_detections():
    every = np.repeat(np.arange(1, 40), 3)  # three rows a frame, every frame
    assert detection_stride(every) == 1
    for k in (2, 3, 5, 30):
        frames = np.arange(7, 7 + 12 * k, k)
        assert detection_stride(np.repeat(frames, 2)) == k
        # one row off the grid: the detector ran on that frame too
        assert detection_stride(np.r_[frames, frames[4] + 1]) == 1
    # a grid with frames where the detector found nothing: still its stride
    assert detection_stride(np.delete(np.arange(1, 100, 4), [3, 4, 9])) == 4
    # too few frames to tell a stride from chance
    assert detection_stride(np.arange(1, 19, 2)) == 1
    assert detection_stride(np.arange(1, 21, 2)) == 2
    assert detection_stride([]) == 1


def test_undelivered_frames_are_runs_without_rows_amid_frames_with_many():
    busy = np.repeat(np.delete(np.arange(1, 31), [4, 11, 12, 19]), 5)  # 5 rows a frame
    assert undelivered_frames(busy).tolist() == [5, 12, 13, 20]
    # runs longer than max_run are left as frames where nothing was found
    assert undelivered_frames(busy, max_run=1).tolist() == [5, 20]
    assert undelivered_frames(busy, max_run=0).tolist() == []
    # 4 rows on one side: the detector may have found nothing there by chance
    sparse = np.r_[busy[busy != 4], 4, 4, 4, 4]
    assert undelivered_frames(sparse).tolist() == [12, 13, 20]
    assert undelivered_frames(sparse, around=4).tolist() == [5, 12, 13, 20]
    # before the first frame with rows and after the last: nothing to tell
    assert undelivered_frames(busy + 10).tolist() == [15, 22, 23, 30]
    # on a detector's grid (every 3rd frame from 2), the grid frames without rows alone
    grid = np.repeat(np.delete(np.arange(2, 60, 3), [3, 7, 8]), 6)
    assert undelivered_frames(grid, first=2, stride=3).tolist() == [11, 23, 26]
    assert undelivered_frames(grid, first=2, stride=3, max_run=1).tolist() == [11]
    assert undelivered_frames([]).tolist() == []


@pytest.mark.parametrize("kw, msg", [(dict(stride=0), "stride must be an integer >= 1; got 0"),
                                     (dict(stride=-1), "stride must be an integer >= 1; got -1"),
                                     (dict(around=0), "around must be an integer >= 1; got 0"),
                                     (dict(max_run=-1), "max_run must be an integer >= 0"),
                                     (dict(first=1.5), "first must be an integer; got 1.5"),
                                     (dict(first=True), "first must be an integer; got True")])
def test_undelivered_frames_names_a_grid_out_of_its_domain(kw, msg):
    """A stride of 0 divided by zero (and returned nothing), -1 returned frames out of order;
    a ``first`` of 1.5 returned nothing, and of 1.0 float frames."""
    with pytest.raises(ValueError, match=msg):
        undelivered_frames(np.repeat([1, 2, 3, 5, 6], 6), **kw)


def test_frame_numbers_that_are_not_whole_are_named():
    """NaN was cast to -2^63 and 3.9 to 3 without a word: frame 2 and frame 4 were reported
    as not delivered (the oracle: the rows' own frames, 1 and 3, and 1, 2, 3.9 and 5, have
    no whole run between frames of 6 rows); a stride was found in frames 2.5, 4.5, ...."""
    import re

    cases = [(np.repeat([1, np.nan, 3], 6), "frames[6] = nan"),
             (np.repeat([1, 2, 3.9, 5], 6), "frames[12] = 3.9"),
             (np.arange(2, 40, 2.0) + 0.5, "frames[0] = 2.5"),
             (np.repeat([1.0, 2.0, 1e19], 6), "frames[12] = 1e+19"),  # cast to -2^63
             (np.repeat(np.array([1, 2, 2 ** 63 + 5], np.uint64), 6),  # wrapped
              "frames[12] = 9.223372036854776e+18")]
    for frames, where in cases:
        for f in (undelivered_frames, detection_stride):
            with pytest.raises(ValueError, match=re.escape(f"frames must be whole numbers below "
                                                           f"2^63; {where}")):
                f(frames)
    # whole numbers as floats, as a MOTChallenge reader gives them, are taken as before
    assert undelivered_frames(np.repeat([1.0, 2.0, 3.0, 5.0, 6.0], 6)).tolist() == [4]
    assert detection_stride(np.arange(1, 40, 3.0)) == 3


def test_duplicate_share_names_an_overlap_out_of_its_domain():
    """NaN and 2 gave 0.0, -1 gave 1.0."""
    from vistrack.detector_checks import duplicate_share
    from vistrack.io.motchallenge import MOTTable

    t = MOTTable.from_rows([(1, -1, 0, 0, 10, 10, 0.9), (1, -1, 1, 0, 10, 10, 0.8)])
    assert duplicate_share(t, 0.5) == 1.0
    for v in (np.nan, 2.0, -1.0, 0.0, "0.5", True):
        with pytest.raises(ValueError, match="min_iou must be a number in \\(0, 1\\]"):
            duplicate_share(t, v)
    assert duplicate_share(t, np.array(0.5)) == 1.0  # a 0-d array, as before
