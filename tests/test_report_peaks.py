"""Peaks reported by ``hbm frf``: resonances by prominence, not every local maximum."""
import numpy as np

from hbm.interface.report import peaks


def _two_modes(f):
    """Two resonances (10 and 25 Hz), the second 50x weaker than the first."""
    return 1.0 / np.abs(10.0 ** 2 - f ** 2 + 0.2j * f) + 0.02 / np.abs(25.0 ** 2 - f ** 2 + 0.5j * f)


def test_ripples_are_not_peaks_but_a_weak_mode_is():
    f = np.linspace(1.0, 40.0, 4001)
    a = _two_modes(f)
    rippled = a * (1.0 + 0.01 * np.sin(2 * np.pi * f / 0.37))    # 1 % ripple: dozens of local maxima
    n_local = np.count_nonzero((rippled[1:-1] > rippled[:-2]) & (rippled[1:-1] >= rippled[2:]))
    assert n_local > 50
    pk = peaks(f, rippled)
    assert len(pk) == 2
    assert abs(pk[0]["freq_hz"] - 10.0) < 0.05 and abs(pk[1]["freq_hz"] - 25.0) < 0.2
    assert pk[1]["amplitude"] < pk[0]["amplitude"] / 10


def test_a_flank_reports_its_largest_value():
    f = np.linspace(1.0, 8.0, 200)
    pk = peaks(f, _two_modes(f))
    assert len(pk) == 1 and pk[0]["freq_hz"] == 8.0
    assert peaks(f[:0], f[:0]) == []


def test_fold_line_names_separate_folds_and_collapses_a_zigzag():
    from hbm.interface.report import describe_folds
    window = (0.0, 1.0)
    zig = list(0.5 + 1e-4 * np.array([0, 1, 0.5, 1.5, 1, 2]))      # 6 turns, each 1e-4 apart
    line = describe_folds([0.2, 0.21] + zig + [0.8], window)
    assert line.startswith("folds at 0.2, 0.21, 0.5..0.5002 (a zigzag of 6 folds, turns of up to 0.0001 Hz), 0.8")
    # two close folds (an S-shaped branch) are both named; so are folds further apart
    assert describe_folds([0.3, 0.3005], window) == "folds at 0.3, 0.3005 Hz"
    assert describe_folds([0.3, 0.302, 0.304], window) == "folds at 0.3, 0.302, 0.304 Hz"
