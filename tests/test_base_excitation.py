"""Base (support) excitation: transmissibility closed form, friction against a moving support,
energy balance with the support's work as the input."""
import numpy as np
import pytest

import hbm
from hbm.interface.case import case_from_dict, CaseError


def base_case(fs=None, kt=50.0, c=0.5, H=5):
    data = {
        "model": {"mass": [[1.0, 0.0], [0.0, 2.0]], "stiffness": [[1000.0, -1000.0], [-1000.0, 1000.0]],
                  "damping": [[c, -c], [-c, c]]},
        "excitation": {"base": {"dofs": [0], "amplitude": [1e-3]}},
        "analysis": {"harmonics": H, "time_samples": 64, "frequency_hz": [1.0, 8.0],
                     "outputs": {"x": 1, "rel": [1, 0]}},
    }
    if fs is not None:
        data["element"] = [{"type": "jenkins", "dofs": [1, 0], "kt": kt, "slip_force": fs}]
    return case_from_dict(data)


def transmissibility(k, c, m, f_hz, Y=1e-3):
    w = 2 * np.pi * f_hz
    return Y * np.abs((k + 1j * w * c) / (k - w * w * m + 1j * w * c))


@pytest.mark.parametrize("fs, k_eff", [(None, 1000.0), (1e9, 1050.0), (0.0, 1000.0)])
def test_transmissibility_closed_form(fs, k_eff):
    res = hbm.frf(base_case(fs))
    assert res.ok, res.message
    ref = transmissibility(k_eff, 0.5, 2.0, res.freq_hz)
    assert np.allclose(res.outputs["x"].h1, ref, rtol=1e-8)
    # the relative output q1 - q0 against its own closed form
    w = 2 * np.pi * res.freq_hz
    rel = 1e-3 * np.abs(w * w * 2.0 / (k_eff - w * w * 2.0 + 1j * w * 0.5))
    assert np.allclose(res.outputs["rel"].h1, rel, rtol=1e-8)


def test_friction_against_moving_support_energy_balance():
    res = hbm.frf(base_case(fs=0.5))
    assert res.ok, res.message
    assert np.all(res.energy_error < 1e-8), res.energy_error.max()
    # friction limits the resonant relative motion below the friction-free peak
    free = hbm.frf(base_case(None))
    assert res.outputs["rel"].h1.max() < 0.8 * free.outputs["rel"].h1.max()


def test_bad_base_excitation():
    good = base_case().raw
    for mutate, needle in [
        (lambda d: d["excitation"]["base"].update(dofs=[5]), "out of range"),
        (lambda d: d["excitation"]["base"].update(speed=1), "speed"),
        (lambda d: d["excitation"]["base"].update(dofs=[0, 1], amplitude=[1e-3, 1e-3]), "nothing is free"),
        (lambda d: d["excitation"]["base"].update(amplitude=[0.0]), "zero"),
    ]:
        import copy
        d = copy.deepcopy(good)
        mutate(d)
        with pytest.raises(CaseError, match=needle):
            case_from_dict(d)
