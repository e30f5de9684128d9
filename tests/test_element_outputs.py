"""Element outputs in ``[analysis] outputs`` ("ELEMENT.QUANTITY"), the element summaries,
weighted coordinates ([[dof, coefficient], ...]) and the frf.csv columns."""
import csv

import numpy as np
import pytest

import hbm
from hbm.interface.case import CaseError, case_from_dict
from hbm.interface.report import write_frf
from elements import Jenkins, CoulombStickSlip, CoulombRegularised, Friction3D, ELEMENTS

C30, S30 = np.cos(np.pi / 6), np.sin(np.pi / 6)


def sdof(outputs, element=None):
    return {
        "name": "sdof",
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[0.05]], "dof_names": ["x.tip"]},
        "element": [element or {"type": "jenkins", "name": "damper", "dofs": [0], "kt": 1.0,
                                "slip_force": 0.3}],
        "excitation": {"dofs": [0], "amplitude": [0.2]},
        "analysis": {"harmonics": 3, "time_samples": 32, "frequency_hz": [0.1, 0.3], "outputs": outputs},
    }


def planar(dofs):
    return {
        "model": {"mass": [[1, 0], [0, 1]], "stiffness": [[1, 0], [0, 2]], "damping": [[0.05, 0], [0, 0.05]],
                  "dof_names": ["x", "y"]},
        "element": [{"type": "friction3d", "name": "wall", "dofs": dofs, "kt": 1.0, "kn": 2.0, "mu": 0.3,
                     "normal_preload": 0.5}],
        "excitation": {"dofs": [0], "amplitude": [0.1]},
        "analysis": {"harmonics": 3, "time_samples": 32, "frequency_hz": [0.1, 0.3], "outputs": {"x": 0}},
    }


# ---------------------------------------------------------------- case schema

def test_element_outputs_are_parsed_beside_dof_outputs():
    case = case_from_dict(sdof({"x": 0, "tip": "x.tip", "slip": "damper.slip_fraction",
                                "work": "damper.dissipation"}))
    # a DOF name with a dot is a DOF: both outputs gather DOF 0
    assert {k: list(v) for k, v in case.analysis.outputs.items()} == {"x": [1.0], "tip": [1.0]}
    assert case.analysis.element_outputs == {"slip": (0, "slip_fraction"), "work": (0, "dissipation")}


@pytest.mark.parametrize("value, words", [
    ("valve.slip_fraction", ["outputs.bad", "'valve'", "'damper'"]),
    ("damper.normal_load_min", ["outputs.bad", "'normal_load_min'", "Jenkins", "slip_fraction"]),
    ("damper", ["outputs.bad", "unknown DOF name 'damper'"]),
])
def test_unknown_element_or_quantity_is_named(value, words):
    with pytest.raises(CaseError) as err:
        case_from_dict(sdof({"x": 0, "bad": value}))
    msg = str(err.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg


def test_ambiguous_element_name_and_column_clash_are_errors():
    data = sdof({"x": 0, "s": "damper.slip_fraction"})
    data["element"].append(dict(data["element"][0]))
    with pytest.raises(CaseError, match="'damper' is not unique"):
        case_from_dict(data)
    with pytest.raises(CaseError, match="'x_h1'"):
        case_from_dict(sdof({"x": 0, "x_h1": "damper.slip_fraction"}))


def test_every_element_type_declares_summary_quantities():
    for key, cls in ELEMENTS.items():
        if getattr(cls, "record", None) is not None:      # conservative laws made from their records
            assert not cls.quantities, key
            continue
        assert cls.quantities, key
        assert "slip_fraction" in cls.quantities and "dissipation" in cls.quantities, key


# ---------------------------------------------------------------- weighted coordinates

def test_weighted_coordinates_build_the_gather_matrix():
    case = case_from_dict(planar({"t1": [[0, C30], [1, S30]], "n": [["x", -S30], ["y", C30]]}))
    G = case.elements[0].gather
    np.testing.assert_array_equal(G, [[C30, S30], [-S30, C30]])
    # the plain forms are unchanged
    G2 = case_from_dict(planar({"t1": [0, 1], "n": "y"})).elements[0].gather
    np.testing.assert_array_equal(G2, [[1, -1], [0, 1]])


@pytest.mark.parametrize("t1, words", [
    ([[0, 0.8, 1]], ["dofs.t1", "[dof, coefficient]"]),
    ([[0, 0.8], [0, 0.5]], ["dofs.t1", "twice"]),
    ([[0, 0.0], [1, 0.0]], ["dofs.t1", "all coefficients are zero"]),
    ([[0, 0.8], 1], ["dofs.t1", "mixes"]),
    ([[0, "a"]], ["dofs.t1", "coefficient of DOF 0"]),
    ([[0, True]], ["dofs.t1", "coefficient"]),
    ([[5, 1.0]], ["dofs.t1", "out of range"]),
    ([["z", 1.0]], ["dofs.t1", "unknown DOF name 'z'"]),
    ([], ["dofs.t1"]),
])
def test_malformed_weighted_coordinates_are_named(t1, words):
    with pytest.raises(CaseError) as err:
        case_from_dict(planar({"t1": t1, "n": 1}))
    for w in words:
        assert w in str(err.value), str(err.value)


# ---------------------------------------------------------------- summaries

TH = 2 * np.pi * np.arange(256) / 256


def march(el, z):
    z = np.ascontiguousarray(z, dtype=float)
    f, _ = el.march(z, np.zeros(z.shape + (1,)))
    return f


@pytest.mark.parametrize("amp", [0.2, 1.0, 3.0])
def test_jenkins_summary_closed_form(amp):
    """u = A cos: stuck below kt A = fs; above, the loop dissipates 4 fs (A - fs / kt) and
    slips over the part of each half period where the slider moves."""
    kt, fs = 1.0, 0.5
    el = Jenkins(np.eye(1), kt=kt, slip_force=fs)
    u = amp * np.cos(TH)[:, None]
    s = el.summary(march(el, u), u)
    if kt * amp <= fs:
        assert s == {"slip_fraction": 0.0, "force_amplitude": pytest.approx(kt * amp, rel=1e-12),
                     "dissipation": pytest.approx(0.0, abs=1e-14)}
    else:
        assert s["dissipation"] == pytest.approx(4 * fs * (amp - fs / kt), rel=1e-3)
        assert s["force_amplitude"] == pytest.approx(fs, rel=1e-12)
        # slips once the force has changed by 2 fs after a reversal: cos(th) < 1 - 2 fs / (kt A)
        th_stick = np.arccos(1 - 2 * fs / (kt * amp))
        assert s["slip_fraction"] == pytest.approx(1 - th_stick / np.pi, abs=2 / TH.size)


def test_coulomb_stick_slip_equal_mu_matches_jenkins():
    u = (1.3 * np.cos(TH) + 0.2 * np.sin(3 * TH))[:, None]
    jen = Jenkins(np.eye(1), kt=2.0, slip_force=0.6)
    cou = CoulombStickSlip(np.eye(1), kt=2.0, normal_load=2.0, mu_static=0.3, mu_kinetic=0.3)
    sj, sc = jen.summary(march(jen, u), u), cou.summary(march(cou, u), u)
    for k in sj:
        assert sc[k] == pytest.approx(sj[k], rel=1e-12, abs=1e-15), k
    assert 0.0 < sj["slip_fraction"] < 1.0


def test_coulomb_regularised_summary():
    """v = -A w sin: far above v_r the force is a square wave, work 4 Ft0 A per cycle."""
    A, w, F0, vr = 1.0, 1.0, 0.5, 1e-3
    el = CoulombRegularised(np.eye(1), slip_force=F0, v_r=vr)
    z = np.column_stack([A * np.cos(TH), -A * w * np.sin(TH)])
    s = el.summary(march(el, z), z)
    assert s["dissipation"] == pytest.approx(4 * F0 * A, rel=2e-3)
    assert s["force_amplitude"] == pytest.approx(F0)
    assert s["slip_fraction"] == pytest.approx(1 - 2 / TH.size)   # v = 0 exactly at 2 samples


def test_friction3d_summary_separation_and_slip():
    el = Friction3D(np.eye(2), kt=1.0, kn=2.0, mu=0.5, normal_preload=1.0)
    z = np.column_stack([2.0 * np.cos(TH), -0.8 * np.cos(TH)])     # opens where 1 + 2 u_n < 0
    f = march(el, z)
    s = el.summary(f, z)
    open_exact = np.mean(1.0 - 1.6 * np.cos(TH) <= 0.0)
    assert s["open_fraction"] == pytest.approx(open_exact)
    assert s["normal_load_min"] == 0.0 and s["normal_load_max"] == pytest.approx(1.0 + 1.6)
    assert 0.0 < s["slip_fraction"] < 1.0 - s["open_fraction"] + 1e-12
    assert np.all(f[1.0 + 2 * z[:, 1] <= 0, 0] == 0.0)               # no friction while open


# ---------------------------------------------------------------- FRF and CSV

def test_frf_element_outputs_and_csv_columns(tmp_path):
    case = case_from_dict(sdof({"x": 0, "slip": "damper.slip_fraction", "work": "damper.dissipation",
                                "f": "damper.force_amplitude"}))
    res = hbm.frf(case)
    assert res.ok, res.message
    n = res.freq_hz.size
    assert set(res.element_outputs) == {"slip", "work", "f"} and set(res.outputs) == {"x"}
    assert all(v.shape == (n,) for v in res.element_outputs.values())
    # stuck at the ends of the range, slipping around resonance; force bounded by the slip limit
    slip = res.element_outputs["slip"]
    assert slip[0] == 0.0 and slip.max() > 0.3
    assert res.element_outputs["f"].max() == pytest.approx(0.3, rel=1e-9)
    write_frf(case, res, tmp_path)
    with open(tmp_path / "frf.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["freq_hz", "x_h1", "x_max", "x_err", "slip", "work", "f", "stuck_contacts", "stable"]
    col = rows[0].index("slip")
    np.testing.assert_allclose([float(r[col]) for r in rows[1:]], slip, rtol=1e-9)


def test_frf_without_element_outputs_keeps_the_contract(tmp_path):
    case = case_from_dict(sdof({"x": 0}))
    res = hbm.frf(case)
    assert res.element_outputs == {}
    write_frf(case, res, tmp_path)
    with open(tmp_path / "frf.csv") as fh:
        assert next(csv.reader(fh)) == ["freq_hz", "x_h1", "x_max", "x_err", "stuck_contacts", "stable"]
