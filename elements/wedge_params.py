r"""Parameters of the wedge (cottage-roof) damper, read and checked from a case table.

Case keys (``[[element]] type = "wedge_damper"``)::

    left  = { x = dof, y = dof, z = dof, rz = dof }   # platform DOFs at the left flank centre
    right = { x = dof, y = dof, z = dof, rz = dof }   # ... right (z on both or neither; rz optional)
    angles_deg = [aL, aR]     # flank angles from the horizontal, degrees, in (0, 90)
    mass = m                  # damper mass, kg
    inertia = J               # in-plane rotational inertia about the CG, kg m^2 (points_per_flank >= 2)
    cf = F                    # radial (centrifugal) load pulling the damper into the groove, N
    mu = 0.3                  # friction coefficient, or [muL, muR]
    kt = ..., kn = ...        # tangential / normal contact stiffness of a whole flank, N/m
    wire_stiffness = Kw       # optional, N/m: radial spring from the damper to ground (seed 003 eq. 1)
    anchor_stiffness = ka     # optional, N/m: tiny spring to ground on every damper DOF (default 1e-6 kn)
    points_per_flank = 1      # 1: 3 translations (implicit model); >= 2: points along each flank + rotation
    flank_length = L          # m, needed when points_per_flank >= 2 (points at -L/2 .. L/2)
    centres = [[xL, yL], [xR, yR]]   # flank centres relative to the CG, m (points_per_flank >= 2)

``rz`` is the platform's in-plane rotation (same sense as the damper's: turning x towards
y), a DOF or weighted DOFs ``{ "blade1.n8.ry" = -1.0 }``; it presses or lifts the points of a
flank (:mod:`elements.wedge`).  With ``points_per_flank = 1`` the keys ``inertia``,
``flank_length``, ``centres`` and ``rz`` are accepted and not used (no rotation DOF, one
point at the flank centre), so a case can switch between the two models.

Axes: ``x`` across the gap (left to right), ``y`` along ``CF`` (towards the platforms), ``z``
axial.  The anchor stiffness fixes the damper's mean position, which friction alone leaves
undetermined while both flanks slip the same way (seed 002); on the rotation it is
``anchor_stiffness (L/2)^2`` N m/rad.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .keys import require_keys, positive, non_negative, finite
from .wedge_statics import static_normal_loads

KEYS = ("type", "name", "left", "right", "angles_deg", "mass", "inertia", "cf", "mu", "kt", "kn",
        "wire_stiffness", "anchor_stiffness", "points_per_flank", "flank_length", "centres")
REQUIRED = ("left", "right", "angles_deg", "mass", "cf", "mu", "kt", "kn")
SIDE_KEYS = ("x", "y", "z", "rz")
ANCHOR_DEFAULT = 1e-6     # anchor_stiffness = ANCHOR_DEFAULT * kn unless given


@dataclass(frozen=True)
class WedgeParams:
    """Checked parameters of a wedge damper (SI units, angles in rad).

    Attributes
    ----------
    angles : tuple of 2 floats
        Flank angles ``(aL, aR)`` from the horizontal, rad.
    mu : tuple of 2 floats
        Friction coefficient per flank.
    centres : ndarray, shape (2, 2) or None
        Flank centres relative to the CG (rows: left, right), m; None for one point per flank.
    three_d : bool
        The platforms have z DOFs: contacts are (t1, t2, n) and the damper has a z DOF.
    """

    angles: tuple
    mass: float
    inertia: float | None
    cf: float
    mu: tuple
    kt: float
    kn: float
    wire_stiffness: float
    anchor_stiffness: float
    points_per_flank: int
    flank_length: float | None
    centres: np.ndarray | None
    three_d: bool

    @property
    def rotates(self) -> bool:
        """The damper's in-plane rotation is a DOF (points spread along the flanks)."""
        return self.points_per_flank >= 2

    @property
    def dof_suffixes(self) -> tuple:
        """Suffixes of the damper DOF names: ``x, y`` (+ ``z``) (+ ``rz``)."""
        return ("x", "y") + (("z",) if self.three_d else ()) + (("rz",) if self.rotates else ())

    def static_normal_loads(self) -> np.ndarray:
        """Flank normal loads ``[N_L, N_R]`` at static equilibrium, N (:mod:`elements.wedge_statics`)."""
        return static_normal_loads(self.cf, self.angles, self.mu)

    def point_offsets(self) -> np.ndarray:
        """Offsets of the contact points along each flank from its centre, m, shape (p,)."""
        if not self.rotates:
            return np.zeros(1)
        h = 0.5 * self.flank_length
        return np.linspace(-h, h, self.points_per_flank)

    def internal_matrices(self):
        """Mass and ground stiffness of the damper DOFs (order of ``dof_suffixes``).

        Returns
        -------
        M : ndarray, shape (n_int, n_int)
            ``diag(m, m, [m], [J])``.
        K : ndarray, shape (n_int, n_int)
            Anchor on every DOF (``k_a``; ``k_a (L/2)^2`` on the rotation) plus the wire on y.
        """
        sfx = self.dof_suffixes
        m = [self.mass if s != "rz" else self.inertia for s in sfx]
        ka = self.anchor_stiffness
        k = [ka * (0.5 * self.flank_length) ** 2 if s == "rz" else ka for s in sfx]
        k[1] += self.wire_stiffness
        return np.diag(m), np.diag(k)


def _sides(spec, where):
    out = []
    for side in ("left", "right"):
        d = spec[side]
        if not isinstance(d, dict):
            raise ValueError(f"{where}: {side} must be a table {{ x = dof, y = dof, z = dof }}, got {d!r}")
        require_keys(d, SIDE_KEYS, ("x", "y"), f"{where}: {side}")
        out.append(d)
    if ("z" in out[0]) != ("z" in out[1]):
        raise ValueError(f"{where}: give z on both left and right, or on neither")
    return out


def parse_params(spec: dict, where: str = "wedge_damper") -> WedgeParams:
    """Check the keys and values of a wedge-damper case table (module docstring).

    Raises
    ------
    ValueError
        Unknown or missing key, bad value (one-line message naming the key).
    """
    require_keys(spec, KEYS, REQUIRED, where)
    left, _ = _sides(spec, where)
    ang = spec["angles_deg"]
    if not (isinstance(ang, (list, tuple)) and len(ang) == 2):
        raise ValueError(f"{where}: angles_deg must be a pair [aL, aR], got {ang!r}")
    angles = []
    for a in ang:
        v = finite("angles_deg", a)
        if not 0.0 < v < 90.0:
            raise ValueError(f"{where}: angles_deg must lie in (0, 90) degrees, got {a!r}")
        angles.append(math.radians(v))
    mu = spec["mu"]
    if isinstance(mu, (list, tuple)):
        if len(mu) != 2:
            raise ValueError(f"{where}: mu must be a number or a pair [muL, muR], got {mu!r}")
        mus = tuple(non_negative("mu", v) for v in mu)
    else:
        mus = (non_negative("mu", mu),) * 2
    try:
        kn = positive("kn", spec["kn"])
        kt = positive("kt", spec["kt"])
        mass = positive("mass", spec["mass"])
        cf = positive("cf", spec["cf"])
        wire = non_negative("wire_stiffness", spec.get("wire_stiffness", 0.0))
        anchor = positive("anchor_stiffness", spec.get("anchor_stiffness", ANCHOR_DEFAULT * kn))
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    p = spec.get("points_per_flank", 1)
    if isinstance(p, bool) or not isinstance(p, int) or p < 1:
        raise ValueError(f"{where}: points_per_flank must be an integer >= 1, got {p!r}")
    inertia = length = centres = None
    if p >= 2:
        for k in ("inertia", "flank_length", "centres"):
            if k not in spec:
                raise ValueError(f"{where}: points_per_flank = {p} needs key {k!r} (the damper rotates)")
        try:
            inertia = positive("inertia", spec["inertia"])
            length = positive("flank_length", spec["flank_length"])
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None
        c = spec["centres"]
        ok = isinstance(c, (list, tuple)) and len(c) == 2 and all(
            isinstance(r, (list, tuple)) and len(r) == 2 for r in c)
        if not ok:
            raise ValueError(f"{where}: centres must be [[xL, yL], [xR, yR]] (m, from the CG), got {c!r}")
        centres = np.array([[finite("centres", v) for v in r] for r in c])
        centres.setflags(write=False)
    params = WedgeParams(tuple(angles), mass, inertia, cf, mus, kt, kn, wire, anchor, p, length,
                         centres, "z" in left)
    try:
        params.static_normal_loads()
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    return params
