"""Case builders of the stress matrix: Jenkins SDOF, a 3-DOF chain with two Jenkins elements,
and a 2-DOF (tangential, normal) point contact with the friction3d element.

All have unit masses and unit structural springs (free natural frequency 1 rad/s on the SDOF),
1 % damping of that mode (``c = 0.02``), and a frequency range from half the free resonance
to 1.5 times the stuck one, so both limits and the transition between them are traced.
The force ratio is ``R = slip force / F`` (excitation amplitude ``F = slip / R``).
"""
from __future__ import annotations

import math

import numpy as np

C = 0.02


def _analysis(H, f_lo, f_hi, outputs):
    return {"harmonics": int(H), "frequency_hz": [f_lo, f_hi], "outputs": outputs}


def jenkins_sdof(ratio: float, slip: float, kt_k: float, H: int) -> dict:
    """``m = k = 1``, Jenkins to ground with ``kt = kt_k``, slip force ``slip``, ``F = slip / ratio``."""
    ws = math.sqrt(1.0 + kt_k)
    return {
        "name": f"jenkins-sdof R={ratio:g} slip={slip:g} kt/k={kt_k:g} H={H}",
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[C]]},
        "element": [{"type": "jenkins", "dofs": [0], "kt": kt_k, "slip_force": slip}],
        "excitation": {"dofs": [0], "amplitude": [slip / ratio]},
        "analysis": _analysis(H, 0.5 / (2 * math.pi), 1.5 * ws / (2 * math.pi), {"x": 0}),
    }


def jenkins_chain3(ratio: float, slip: float, kt_k: float, H: int) -> dict:
    """Ground-k-m0-k-m1-k-m2; Jenkins from m0 to ground and between m1 and m2 (both ``kt``,
    ``slip``); excitation ``F = slip / ratio`` on m2; outputs all three masses."""
    K = [[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]]
    Ks = np.array(K) + kt_k * np.array([[1, 0, 0], [0, 1, -1], [0, -1, 1]])
    w_free = np.sqrt(np.linalg.eigvalsh(np.array(K)))
    w_stuck = np.sqrt(np.linalg.eigvalsh(Ks))
    return {
        "name": f"jenkins-chain3 R={ratio:g} slip={slip:g} kt/k={kt_k:g} H={H}",
        "model": {"mass": np.eye(3).tolist(), "stiffness": K, "damping": (C * np.eye(3)).tolist()},
        "element": [{"type": "jenkins", "dofs": [0], "kt": kt_k, "slip_force": slip},
                    {"type": "jenkins", "dofs": [1, 2], "kt": kt_k, "slip_force": slip}],
        "excitation": {"dofs": [2], "amplitude": [slip / ratio]},
        "analysis": _analysis(H, 0.5 * w_free[0] / (2 * math.pi), 1.5 * w_stuck[-1] / (2 * math.pi),
                              {"x0": 0, "x1": 1, "x2": 2}),
    }


def friction3d_2dof(ratio: float, kt_k: float, H: int, separation: bool, kn_k: float = 1.0) -> dict:
    """Point contact to ground: tangential mass (dof 0) and normal mass (dof 1), unit springs.

    Excitation ``F`` on both dofs (cosine, in phase).  The normal preload is set from the
    largest dynamic normal contact force of the closed linear system on the frequency range,
    ``Nd = max kn |x_n|``: ``N0 = 0.2 Nd`` (the contact opens: separation) or ``N0 = 10 Nd``
    (it stays closed); ``mu = ratio F / N0`` so that the force ratio is ``mu N0 / F = ratio``.
    """
    F = 1.0
    ws = math.sqrt(1.0 + kt_k)
    f_lo, f_hi = 0.5 / (2 * math.pi), 1.5 * max(ws, math.sqrt(1.0 + kn_k)) / (2 * math.pi)
    w = 2 * math.pi * np.linspace(f_lo, f_hi, 4001)
    xn = F / np.abs(1.0 + kn_k - w ** 2 + 1j * C * w)
    Nd = float(kn_k * xn.max())
    N0 = (0.2 if separation else 10.0) * Nd
    mu = ratio * F / N0
    return {
        "name": f"friction3d R={ratio:g} kt/k={kt_k:g} H={H} {'separating' if separation else 'closed'}",
        "model": {"mass": np.eye(2).tolist(), "stiffness": np.eye(2).tolist(), "damping": (C * np.eye(2)).tolist()},
        "element": [{"type": "friction3d", "dofs": {"t1": 0, "n": 1}, "kt": kt_k, "kn": kn_k, "mu": mu,
                     "normal_preload": N0}],
        "excitation": {"dofs": [0, 1], "amplitude": [F, F]},
        "analysis": _analysis(H, f_lo, f_hi, {"t": 0, "n": 1}),
    }
