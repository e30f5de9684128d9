"""Default H and N per element type: a case without ``harmonics`` / ``time_samples`` takes the
largest default over its elements; given values (case or argument) always win."""
import numpy as np
import pytest

import hbm
from elements import ELEMENTS, Element, Jenkins, Cubic
from hbm.interface.case import case_from_dict, element_defaults, CaseError, LINEAR_DEFAULT
from hbm.balance.fourier import default_samples
from hbm.interface.report import summary_dict

JENKINS = {"type": "jenkins", "dofs": [0], "kt": 2.0, "slip_force": 0.3}
CUBIC = {"type": "cubic", "dofs": [1], "k3": 0.01}


def two_dof(elements, **analysis):
    return case_from_dict({
        "model": {"mass": [[1.0, 0.0], [0.0, 1.0]], "stiffness": [[2.0, -1.0], [-1.0, 2.0]],
                  "damping": [[0.02, 0.0], [0.0, 0.02]]},
        "element": elements,
        "excitation": {"dofs": [0], "amplitude": [0.5]},
        "analysis": {"frequency_hz": [0.1, 0.3], "outputs": {"x": 0}, **analysis},
    })


def test_every_registered_element_states_its_defaults():
    for key, cls in ELEMENTS.items():
        assert "default_harmonics" in vars(cls), key           # measured, not inherited
        assert "default_samples_factor" in vars(cls), key
        assert int(cls.default_harmonics) >= 1 and int(cls.default_samples_factor) >= 1


def test_element_defaults_is_the_max_over_elements():
    class A(Jenkins):
        default_harmonics, default_samples_factor = 9, 1

    class B(Jenkins):
        default_harmonics, default_samples_factor = 3, 4

    a, b = A(np.eye(1), 1.0, 0.1), B(np.eye(1), 1.0, 0.1)
    assert element_defaults([a]) == (9, 1)
    assert element_defaults([b]) == (3, 4)
    assert element_defaults([a, b]) == element_defaults([b, a]) == (9, 4)   # H from A, factor from B
    assert element_defaults([]) == LINEAR_DEFAULT == (1, 1)
    # a class without its own table keeps the former loader default
    assert (Element.default_harmonics, Element.default_samples_factor) == (5, 1)


def test_loader_takes_the_largest_element_default():
    for specs in ([JENKINS], [CUBIC], [JENKINS, CUBIC]):
        case = two_dof(specs)
        classes = [ELEMENTS[s["type"]] for s in specs]
        H = max(c.default_harmonics for c in classes)
        fac = max(c.default_samples_factor for c in classes)
        np.testing.assert_array_equal(case.analysis.harmonics, np.arange(1, H + 1))
        assert case.analysis.time_samples == default_samples([H], fac) == fac * max(64, 8 * H)
        assert case.analysis.harmonics_source == case.analysis.samples_source == "default"
        assert case.analysis.samples_factor == fac


def test_linear_case_defaults_to_the_first_harmonic():
    case = two_dof([])
    np.testing.assert_array_equal(case.analysis.harmonics, [1])
    assert case.analysis.time_samples == 64


def test_given_values_win():
    case = two_dof([JENKINS, CUBIC], harmonics=7, time_samples=96)
    np.testing.assert_array_equal(case.analysis.harmonics, np.arange(1, 8))
    assert case.analysis.time_samples == 96
    assert case.analysis.harmonics_source == case.analysis.samples_source == "case"
    # H given, N not: N follows the given H with the elements' factor
    fac = max(Jenkins.default_samples_factor, Cubic.default_samples_factor)
    case = two_dof([JENKINS, CUBIC], harmonics=[1, 3, 5, 7, 9, 11, 13, 15, 17])
    assert case.analysis.time_samples == fac * 256
    assert (case.analysis.harmonics_source, case.analysis.samples_source) == ("case", "default")
    # N given, H not
    case = two_dof([JENKINS], time_samples=40)
    assert case.analysis.time_samples == 40 and case.analysis.samples_source == "case"
    assert case.analysis.harmonics.max() == Jenkins.default_harmonics
    # a default H whose default N a given N cannot resolve is reported, not silently changed
    with pytest.raises(CaseError, match="time_samples"):
        two_dof([JENKINS], time_samples=2 * Jenkins.default_harmonics)


def test_frf_settings_say_where_h_and_n_came_from():
    case = two_dof([JENKINS], frequency_hz=[0.1, 0.12])
    res = hbm.frf(case, stability=False)
    st = res.settings
    H = Jenkins.default_harmonics
    assert st["harmonics"] == list(range(1, H + 1))
    assert st["time_samples"] == default_samples([H], Jenkins.default_samples_factor)
    assert (st["harmonics_source"], st["time_samples_source"]) == ("default", "default")
    assert summary_dict(case, res)["settings"]["harmonics_source"] == "default"
    # an argument wins over the defaults; N then follows the argument's H
    st = hbm.frf(case, harmonics=11, stability=False).settings
    assert st["harmonics"][-1] == 11 and st["harmonics_source"] == "argument"
    assert st["time_samples"] == Jenkins.default_samples_factor * 128
    assert st["time_samples_source"] == "default"
    st = hbm.frf(case, harmonics=2, samples=48, stability=False).settings
    assert (st["time_samples"], st["time_samples_source"]) == (48, "argument")
    # given in the case: "case", and a larger H from an argument keeps the case's N if larger
    given = two_dof([JENKINS], frequency_hz=[0.1, 0.12], harmonics=3, time_samples=512)
    st = hbm.frf(given, harmonics=5, stability=False).settings
    assert (st["harmonics_source"], st["time_samples"], st["time_samples_source"]) == ("argument", 512, "case")


def test_default_samples_factor():
    assert default_samples([1]) == 64 and default_samples([1], 2) == 128
    assert default_samples([21], 2) == 512
    for bad in (0, 1.5, True):
        with pytest.raises(ValueError, match="factor"):
            default_samples([3], bad)
