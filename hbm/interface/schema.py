"""The case-file schema: every key the loader accepts, with its meaning, in one place.

The loader (:mod:`hbm.interface.case`) validates the top level, ``[model]``, ``[excitation]`` and
``[analysis]`` against the key lists here; elements and model builders validate against their
own classes' ``keys``, and :func:`reference` refuses to write the reference when one of those
keys has no entry here (or an entry names a key the class does not take).  The document
``docs/case-reference.md`` is written from here (``python docs/make_reference.py``) and a test
compares the two, so it cannot drift from what the loader accepts.
"""
from __future__ import annotations

from elements.laws.registry import CASE_LAWS

TABLES = {
    "top level": {
        "name": "string; the case's title in outputs and plots (default: the file name)",
        "model": "table: the linear structure",
        "element": "array of tables `[[element]]`: the nonlinear elements (optional: a linear case)",
        "excitation": "table: the harmonic force or support motion",
        "analysis": "table: harmonics, frequency window, outputs",
    },
    "[model]": {
        "mass": "matrix (n x n), or a vector for a diagonal matrix; kg",
        "stiffness": "matrix (n x n), or a vector for a diagonal matrix; N/m",
        "damping": "matrix (n x n), or a vector; N s/m (one damping form only)",
        "rayleigh": "`[a, b]`: C = a M + b K",
        "modal_damping": "damping ratio z, or `[z1, z2, ...]` per mode (the last repeats)",
        "dof_names": "list of n strings naming the DOFs (then any DOF may be given by name)",
        "file": "model file beside the case: `x.npz` (arrays M, K [, C, dof_names]), Matrix Market "
                "`x_K.mtx` with `x_M.mtx` [, `x_C.mtx`], or Nastran `x.op4`",
        "builder": "`\"beam\"`: assemble from `[[model.beam]]`, `[[model.body]]`, `[[model.spring]]`",
        "beam": "array of tables: Euler-Bernoulli beams (builder = \"beam\"; keys below)",
        "body": "array of tables: rigid bodies (builder = \"beam\"; keys below)",
        "spring": "array of tables: springs between points (builder = \"beam\"; keys below)",
        "solver": "`\"auto\"` (default: condensed above 60 DOFs), `\"full\"` or `\"condensed\"`",
        "modes": "modes kept by the condensed solver: an integer (default 40) or `\"all\"`",
        "residual_flexibility": "bool (default true): static correction of the truncated modes",
    },
    "[excitation]": {
        "dofs": "list of DOFs (indices or names) that carry the force",
        "amplitude": "list of force amplitudes, N, one per DOF (cosine at the first harmonic)",
        "phase_deg": "list of phases, degrees, one per DOF (default 0): F_i cos(w t - phase_i); "
                     "engine-order excitation of a sector has phase_i = 360 EO i / N_blades",
        "base": "table `{ dofs = [...], amplitude = [...] }`: imposed support motion, m (full solver)",
    },
    "[excitation] base": {
        "dofs": "list of single DOFs that move (the supports)",
        "amplitude": "list of displacement amplitudes, m (cosine at the first harmonic)",
    },
    "[analysis]": {
        "harmonics": "H (harmonics 1..H, plus 0 when an element needs the mean) or a list; "
                     "default: the elements' own default",
        "time_samples": "samples per period N of the AFT (default: from H and the elements)",
        "frequency_hz": "`[fmin, fmax]`, Hz: the window traced by the continuation",
        "outputs": "table `name = DOF`, `name = [a, b]` (q_a - q_b), `name = [[a, ca], [b, cb]]` "
                   "(combination) or `name = \"ELEMENT.QUANTITY\"` (per-period element output)",
        "max_points": "most points on the path (default 2000)",
        "transform": "AFT transform: `\"auto\"` (default), `\"dft\"`, `\"numpy\"` or `\"fftw\"` (pyFFTW)",
    },
}

ELEMENT_KEYS = {
    "type": "the element type (this section's heading)",
    "name": "name for outputs (`\"NAME.QUANTITY\"`) and internal DOFs",
    "dofs": "where the element acts: a DOF, `[a, b]` (relative), `[[a, ca], ...]`, or a table of "
            "local directions (`t1`, `t2`, `n`, ...) each given so",
}

ELEMENTS = {
    "jenkins": {"kt": "tangential stiffness, N/m", "slip_force": "slip force, N",
                "aft": "`\"sampled\"` (default: the law marched over the time samples) or "
                       "`\"events\"` (forces integrated exactly between the reversal and slip "
                       "events: no sampling error, for stiff contacts and the Coulomb limit)"},
    "friction3d": {"kt": "tangential stiffness, N/m", "kn": "normal stiffness, N/m",
                   "mu": "friction coefficient", "normal_preload": "static normal load N0 >= 0, N "
                   "(the contact opens when N0 + kn (u_n - g) falls to 0)",
                   "normal_gap": "optional initial normal gap g, m (default 0): > 0 open at rest, "
                   "< 0 an interference (static load N0 - kn g)",
                   "aft": "`\"sampled\"` (default) or, on a (t1, n) contact, `\"events\"` (forces "
                          "integrated exactly between slip, stick, opening and re-contact events: no "
                          "sampling error, for stiff and rigid contacts)"},
    "coulomb_stick_slip": {"kt": "stick stiffness, N/m", "normal_load": "normal load, N",
                           "mu_static": "static friction coefficient",
                           "mu_kinetic": "kinetic friction coefficient"},
    "coulomb_regularised": {"slip_force": "slip force, N", "v_r": "regularisation velocity, m/s",
                            "law": "`\"linear\"` (saturation, default), `\"arctan\"` or `\"tanh\"`"},
    "brush": {"mu": "friction coefficient", "normal_preload": "total static normal load N0, N",
              "radius_x": "indenter radius of curvature along t1, m (`inf`: flat)",
              "radius_y": "indenter radius of curvature along t2, m (`inf`: flat)",
              "lx": "half extent of the bristle grid along t1, m (must cover the contact)",
              "ly": "half extent of the bristle grid along t2, m", "nx": "bristles along t1",
              "ny": "bristles along t2", "kn": "normal stiffness per bristle, N/m (or e_star)",
              "kt": "tangential stiffness per bristle, N/m (or e_star)",
              "e_star": "Hertz-equivalent modulus, Pa: bristle stiffnesses from it",
              "gamma_n": "normal stiffness factor with e_star (default: the Hertz contact area)",
              "gamma_t": "tangential stiffness factor with e_star",
              "pivot_height": "height of the rotation centre above the contact, m (default 0)"},
    "wedge_damper": {"left": "table `{x, y [, z] [, rz]}`: the left platform's DOFs at the flank "
                             "centre (rz: its in-plane rotation)",
                     "right": "table `{x, y [, z] [, rz]}`: the right platform's DOFs",
                     "angles_deg": "`[aL, aR]`: flank angles from the horizontal, degrees",
                     "mass": "damper mass, kg", "inertia": "damper inertia, kg m^2 (rotating damper)",
                     "cf": "centrifugal load on the damper, N", "mu": "friction coefficient, or `[muL, muR]`",
                     "kt": "tangential contact stiffness per flank, N/m", "kn": "normal contact stiffness per flank, N/m",
                     "wire_stiffness": "damper y to ground, N/m (optional)",
                     "anchor_stiffness": "every damper DOF to ground, N/m (default 1e-6 kn)",
                     "points_per_flank": "contact points per flank (>= 2: the damper rotates)",
                     "flank_length": "flank length L, m (points_per_flank >= 2)",
                     "centres": "`[[xL, yL], [xR, yR]]`: flank centres from the damper's CG, m"},
    # laws registered as case types document their parameters in their records
    **{rec.name: {key: doc for key, _, doc in rec.params} for rec in CASE_LAWS.values()},
}

BUILDER = {
    "[[model.beam]]": ("BEAM_KEYS", {
        "name": "beam name (nodes are `NAME.nK`, DOFs `NAME.nK.ux`...)", "length": "m",
        "n_elements": "number of beam elements", "E": "Young's modulus, Pa", "rho": "density, kg/m^3",
        "nu": "Poisson's ratio (default 0.3)", "width": "rectangular section width, m",
        "height": "rectangular section height, m", "area": "section area, m^2 (instead of width/height)",
        "Iy": "second moment about y, m^4", "Iz": "second moment about z, m^4", "J": "torsion constant, m^4",
        "clamp": "clamped end(s)", "origin": "position of the first node, m", "axis": "beam axis direction",
        "up": "section's up direction", "lumped_mass": "bool: lumped instead of consistent mass",
        "points": "table of named points `{node, offset}` (coordinates `NAME.POINT.x`...)",
        "point_masses": "point masses on nodes, kg"}),
    "[[model.body]]": ("BODY_KEYS", {"name": "body name", "mass": "kg", "inertia": "kg m^2"}),
    "[[model.spring]]": ("SPRING_KEYS", {"between": "the two points or DOFs joined",
                                         "k": "translational stiffness, N/m", "k_rot": "rotational stiffness"}),
}


def table_keys(table: str) -> tuple:
    """The keys the loader accepts in ``table`` (a key of :data:`TABLES`)."""
    return tuple(TABLES[table])


def _check(where: str, documented, accepted) -> None:
    missing, extra = set(accepted) - set(documented), set(documented) - set(accepted)
    if missing or extra:
        raise RuntimeError(f"schema of {where} out of date: undocumented {sorted(missing)}, "
                           f"not accepted {sorted(extra)}")


def _section(title: str, rows: dict, lines: list) -> None:
    lines += [f"### {title}", "", "| key | meaning |", "|---|---|"]
    lines += [f"| `{k}` | {v.replace('|', '/')} |" for k, v in rows.items()]
    lines.append("")


def reference() -> str:
    """The case-file reference (Markdown), checked against the element and builder classes."""
    from elements import ELEMENTS as CLASSES
    from hbm.builders import assembly
    _check("element types", ELEMENTS, CLASSES)
    lines = ["# Case-file reference", "",
             "Generated by `python docs/make_reference.py` from `hbm/interface/schema.py`, the key lists the loader "
             "validates against; do not edit by hand. Every key not listed is an error naming it.",
             "Units are SI; a DOF is an index or a name; matrices are nested lists.", "",
             "## Tables", ""]
    for title, rows in TABLES.items():
        _section(title, rows, lines)
    lines += ["## Model builder (`builder = \"beam\"`)", ""]
    for title, (attr, rows) in BUILDER.items():
        _check(title, rows, getattr(assembly, attr))
        _section(title, rows, lines)
    lines += ["## Elements (`[[element]]`, by `type`)", ""]
    for kind, rows in ELEMENTS.items():
        cls = CLASSES[kind]
        full = {k: ELEMENT_KEYS[k] for k in cls.keys if k in ELEMENT_KEYS} | rows
        _check(f"element {kind}", full, cls.keys)
        doc = (cls.__doc__ or "").strip().split("\n\n")[0].replace("\n", " ")
        lines += [f"### `{kind}`", "", doc, ""]
        quantities = getattr(cls, "quantities", ())
        if quantities:
            lines += ["Outputs `\"NAME.QUANTITY\"`: " + ", ".join(f"`{q}`" for q in quantities) + ".", ""]
        _section(f"`{kind}` keys", full, lines)
    return "\n".join(lines).rstrip() + "\n"

