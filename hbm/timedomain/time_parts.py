r"""The elements as the time integrator sees them: law parts with their gathers.

An element offers its parts (:meth:`elements.base.Element.time_parts`): part ``p`` reads
``z_p = R_p z_e`` of the element's local coordinates ``z_e = G_e q`` and steps one law, so
its gather is ``G_p = R_p G_e``, and the element force is

.. math::

    f_e = \sum_{p \in e} R_p^T f_p, \qquad \sum_e G_e^T f_e = \sum_p G_p^T f_p .

A plain element is one part (``R = I``); a wedge is its flank contacts (rows of ``I``); a
brush is its bristles (each a friction3d contact reading the tangential coordinates and its
own approach).  :func:`pack_elements` flattens the parts into the arrays of the compiled
kernels (:mod:`hbm.timedomain.time_kernels`) and the map back to element forces for the records.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hbm.interface.case import CaseError


@dataclass(frozen=True)
class Packed:
    """Flat arrays of the law parts, one entry per part (offsets have ``n_parts + 1``).

    Attributes
    ----------
    laws : tuple
        ``(kinds, p_all, p_off, s_off, g_all, g_off, vel, d_off)``: law ids (n_parts,),
        parameters, states, gather rows ``g_all`` (n_rows, n_dof), stored-tangent slots.
    r_all, r_off, o_off : ndarray
        ``R_p`` flattened (row-major, (n_part_rows, n_local of its element)) at ``r_off[p]``;
        its element's first output column ``o_off[p]``.
    g_out : ndarray, shape (n_out, n_dof)
        Every element's gather, stacked: the recorded coordinates.
    names : tuple of str
        ``n_out`` labels of the element force components.
    """

    laws: tuple
    r_all: np.ndarray
    r_off: np.ndarray
    o_off: np.ndarray
    g_out: np.ndarray
    names: tuple

    @property
    def n_states(self) -> int:
        return int(self.laws[3][-1])

    @property
    def n_tangents(self) -> int:
        return int(self.laws[7][-1])

    @property
    def n_parts(self) -> int:
        return int(self.laws[0].size)

    def record_map(self) -> tuple:
        return self.r_all, self.r_off, self.o_off, self.g_out


def force_labels(element) -> tuple:
    """``NAME_f`` for a one-coordinate element, else ``NAME_f_COORD`` per local coordinate."""
    if element.n_local == 1:
        return (f"{element.name}_f",)
    names = tuple(element.coord_names) if len(element.coord_names) == element.n_local else \
        tuple(str(i) for i in range(element.n_local))
    return tuple(f"{element.name}_f_{c}" for c in names)


def _parts(element):
    parts = element.time_parts()
    if not parts:
        raise CaseError(f"element {element.name}: {type(element).__name__} has no time-step law; "
                        f"the time-domain reference does not support it")
    return [(np.asarray(R, dtype=float), spec) for R, spec in parts]


def pack_elements(elements, n_dof: int) -> Packed:
    """The elements' law parts as the kernels' flat arrays (:class:`Packed`)."""
    kinds, params, ns, G, vel, R, o_off, names, g_out = [], [], [], [], [], [], [], [], []
    col = 0
    for e in elements:
        for Rp, spec in _parts(e):
            kinds.append(spec.kind)
            params.append(np.asarray(spec.params, dtype=float))
            ns.append(spec.n_state)
            G.append(Rp @ e.gather)
            vel.append(1 if spec.velocity else 0)
            R.append(Rp.ravel())
            o_off.append(col)
        col += e.n_local
        names += force_labels(e)
        g_out.append(e.gather)
    n_rows = np.array([g.shape[0] for g in G], dtype=np.int64)
    d_size = np.array([r * r * (2 if v else 1) for r, v in zip(n_rows, vel)], dtype=np.int64)

    def offsets(sizes):
        return np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)

    laws = (np.array(kinds, dtype=np.int64),
            np.ascontiguousarray(np.concatenate(params) if params else np.zeros(0)),
            offsets([p.size for p in params]), offsets(ns),
            np.ascontiguousarray(np.vstack(G) if G else np.zeros((0, n_dof))),
            offsets(n_rows), np.array(vel, dtype=np.int64), offsets(d_size))
    return Packed(laws, np.ascontiguousarray(np.concatenate(R) if R else np.zeros(0)),
                  offsets([r.size for r in R]), np.array(o_off, dtype=np.int64),
                  np.ascontiguousarray(np.vstack(g_out) if g_out else np.zeros((0, n_dof))),
                  tuple(names))
