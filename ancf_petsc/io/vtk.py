"""ParaView output: the deformed beam surfaces (sections sampled along ξ) and the contact points,
as VTU time series with .pvd collections (``vtu.write_vtu``: meshio's layout, without its import)."""
from __future__ import annotations

import os
import re
import time

import numpy as np

from ..contact.partners import HISTORY
from ..model.beams import Model
from ..model.fibre_setup import directions_at
from ..physics import element3363 as el
from ..physics.axial_shear import axial_shear_for
from ..physics.cubature import gauss_legendre
from ..physics.materials import det_and_inverse_transpose, determinant
from ..physics.mixed import grouped_basis, pressure_basis
from .files import atomic_write, os_reason, remove_quietly
from .surface_fields import SampledState, fields_for
from .vtu import cells_xml, write_vtu


class SurfaceSampler:
    """Quad surface (plus end caps) of each beam, sampled ``samples`` times per element.  The
    shape functions and reference gradients at the sample points are computed once."""

    def __init__(self, model: Model, samples: int):
        self.model = model
        self.parts = []
        self._cells = None                  # (quads, caps): ``_topology``
        self.cell_blocks = None             # the VTU cell blocks: ``surface_cells``
        block = model.block
        SLOTS, k = block.slots, block.axial_nodes - 1
        for beam in model.beams:
            xi = np.linspace(-1.0, 1.0, samples + 1)
            conn = beam.connectivity
            E = len(conn)
            if beam.ring_at is not None:            # the outline at every sampled x, per element
                x = beam.x_nodes[0:-1:k, None] + 0.5 * (xi[None, :] + 1.0) * (beam.x_nodes[k] - beam.x_nodes[0])
                YZ = np.stack([np.concatenate([beam.ring_at(xx) for xx in row]) for row in x])
                m = YZ.shape[1] // len(xi)
            else:
                ring = beam.section.boundary_polyline(6)
                if np.allclose(ring[0], ring[-1]):
                    ring = ring[:-1]
                m = len(ring)
                YZ = np.broadcast_to(np.tile(ring, (len(xi), 1)), (E, len(xi) * m, 2))
            M = len(xi) * m
            N, dN = block.shape_functions(np.tile(np.repeat(xi, m), E), YZ[..., 0].ravel(), YZ[..., 1].ravel())
            q0e = model.q0[conn].reshape(E, SLOTS, 3)
            G, _ = el.reference_gradients(q0e, dN.reshape(E, M, SLOTS, 3))
            # drop the duplicated first station of every element but the first
            keep = np.concatenate([np.arange(M)] + [e * M + np.arange(m, M) for e in range(1, E)])
            N, e_of = N[keep], keep // M
            r0 = np.einsum("pa,pai->pi", N, q0e[e_of])          # reference points, once
            law = self._fibre_law(beam, xi, m, YZ, keep)
            theta = StationDilatation(beam, block, xi, YZ, q0e, keep) if law and beam.locking == "mixed" else None
            axis = self._fibre_law(beam, xi, m, np.zeros(np.shape(YZ)), keep) if beam.locking == "ecm" else None
            ecm = AxialRecovery(beam, block, xi, YZ, q0e, keep, axis) if law and beam.locking != "mixed" else None
            self.parts.append((beam, m, len(xi) - 1, N, G.reshape(-1, SLOTS, 3)[keep], e_of, r0, law, theta, ecm))

    def _fibre_law(self, beam, xi, m, YZ, keep):
        """A fibre-reinforced beam's law bound to its fibre directions at the sample points."""
        if beam.fibres is None:
            return None
        spec = self.model.spec
        k = self.model.block.axial_nodes - 1
        x0, h = beam.x_nodes[0:-1:k], beam.x_nodes[k] - beam.x_nodes[0]
        x = x0[:, None] + 0.5 * (np.repeat(xi, m)[None, :] + 1.0) * h                   # (E, M)
        a0 = directions_at(beam, x, np.asarray(YZ), spec.length, spec.twist_deg, spec.twist_axis)
        return beam.material.with_directions(a0.reshape(a0.shape[0], -1, 3)[:, keep])

    def mesh(self, q: np.ndarray):
        """points (n, 3), quads (k, 4), caps list, point data dict for nodal vectors q: the
        fields of ``surface_fields.SURFACE_FIELDS`` that apply to these beams (the quads and
        caps are the same arrays at every call)."""
        states = []
        for beam, m, S, N, G, e_of, r0, law, theta, ecm in self.parts:
            conn = beam.connectivity
            qe = q[conn].reshape(len(conn), self.model.block.slots, 3)
            r = np.einsum("pa,pai->pi", N, qe[e_of])
            F = np.matmul(np.swapaxes(qe[e_of], 1, 2), G)
            states.append(SampledState(r, r0, F, beam.index, law, None if theta is None else theta.at(qe),
                                       None if ecm is None else ecm.stress(qe[e_of], F, law)))
        quads, caps = self._topology()
        data = {f.name: np.concatenate([f.values(s) for s in states]) for f in fields_for(states)}
        return np.concatenate([s.r for s in states]), quads, caps, data

    def _topology(self) -> tuple[np.ndarray, list]:
        """The quads (k, 4) and end caps of every beam's sampled surface, made once."""
        if self._cells is None:
            quads, caps = [], []
            offset = 0
            for beam, m, S, N, *_ in self.parts:
                n_st = beam.n_elements * S + 1
                st = np.arange(n_st - 1)[:, None]
                j = np.arange(m)[None, :]
                a = st * m + j
                b = st * m + (j + 1) % m
                quads.append(offset + np.stack([a, b, b + m, a + m], axis=-1).reshape(-1, 4))
                caps.append(offset + np.arange(m)[::-1])
                caps.append(offset + (n_st - 1) * m + np.arange(m))
                offset += len(N)
            self._cells = (np.concatenate(quads), caps)
        return self._cells


class AxialRecovery:
    """The stress at a beam's surface samples as the solution determines it (``locking: none`` and
    ``ecm``): the Cauchy stress at the axial Gauss stations (the sample's own y, z and fibres),
    interpolated along ξ between them (Lagrange through the stations).  The element's own F at
    other stations is not held by the solve (the quadrature sees the stations only): at element
    ends the fibre stress from it was up to 34x beam theory's on a nearly incompressible
    cantilever, mostly the matrix's pressure K (J − 1) (docs/fibres.md, "Output").  With ``ecm``
    (``axis_law``: the law bound to the axis' fibres) the stress is that of the energy it solves,
    P₀(F) + P(F_a) − P₀(F_a) (model.Beam.parts: Ψ₀ the ν = 0 law over the section, Ψ − Ψ₀ on the
    axis, F_a on the axis at the station; Ψ₀ with its axial-shear part, physics/axial_shear.py):
    the law's own P(F) there is the stress of 3333's locked lateral strains, 1.6-2.2x beam
    theory's on the same cantilever."""

    def __init__(self, beam, block, xi: np.ndarray, YZ, q0e: np.ndarray, keep: np.ndarray, axis_law=None):
        E, n = len(q0e), np.shape(YZ)[1]
        xa = gauss_legendre(beam.axial_points)[0]
        y, z = (np.asarray(YZ)[..., k].ravel() for k in (0, 1))

        def gradients(g, y, z):
            _, dN = block.shape_functions(np.full(len(y), g), y, z)
            return el.reference_gradients(q0e, dN.reshape(E, n, block.slots, 3))[0].reshape(-1, block.slots, 3)[keep]
        self.G = [gradients(g, y, z) for g in xa]
        self.G_axis = None if axis_law is None else [gradients(g, 0.0 * y, 0.0 * z) for g in xa]
        self.axis_law, self.axis_free = axis_law, None if axis_law is None else axis_law.poisson_free()
        xs = np.tile(np.repeat(xi, n // len(xi)), E)[keep]                 # each sample's ξ
        self.ell = np.stack([np.prod([(xs - b) / (a - b) for b in xa if b != a], axis=0) for a in xa])

    def stress(self, qe: np.ndarray, F: np.ndarray, law) -> np.ndarray:
        """P (n, 3, 3) at the samples with deformation gradient F whose Cauchy stress is the
        stations' interpolated, for their elements' nodal vectors qe (n, S, 3)."""
        qt, sigma = np.swapaxes(qe, 1, 2), 0.0
        with np.errstate(over="ignore", invalid="ignore"):
            for k, (ell, G) in enumerate(zip(self.ell, self.G)):
                Fg = np.matmul(qt, G)
                if self.G_axis is None:
                    P, J = law.stress(Fg)
                else:
                    Fa = np.matmul(qt, self.G_axis[k])
                    free = law.poisson_free()
                    P0, J = free.stress(Fg)
                    P = P0 + self.axis_law.stress(Fa)[0] - self.axis_free.stress(Fa)[0]
                    shear = axial_shear_for(law, free)         # its shear part (physics/axial_shear.py)
                    if shear is not None:
                        P = P + shear.stress(Fg)[0] - shear.stress(Fa)[0]
                sigma = sigma + (ell / J)[:, None, None] * np.matmul(P, np.swapaxes(Fg, 1, 2))
            J, H = det_and_inverse_transpose(F)
            return J[:, None, None] * np.matmul(sigma, H)


class StationDilatation:
    """θ of ``locking: mixed`` (physics/mixed.py) at a beam's surface samples: J over the section
    rule at each sampled station, projected onto the pressure space (at an axial Gauss station the
    solver's θ).  Without it the fibre stress took the pointwise K (J − 1): 24 % off the solved
    stress on a 180 deg pretwisted GOH bar."""

    def __init__(self, beam, block, xi: np.ndarray, YZ, q0e: np.ndarray, keep: np.ndarray):
        E, S1 = len(q0e), len(xi)
        yz = np.broadcast_to(beam.yz, (E,) + beam.yz.shape[-2:])
        wq = np.broadcast_to(beam.wq, (E,) + beam.wq.shape[-1:])
        n = yz.shape[1] // beam.axial_points                     # one station's section rule
        sec, w = np.broadcast_to(yz[:, None, :n], (E, S1, n, 2)), np.broadcast_to(wq[:, None, :n], (E, S1, n))
        ring = np.asarray(YZ).reshape(E, S1, -1, 2)
        pts = np.concatenate([sec, ring], axis=2)                # the ring weightless: same centring
        wts = np.concatenate([w, np.zeros(ring.shape[:3])], axis=2)
        phi = pressure_basis(pts, wts, 1) if beam.pressure_columns is None \
            else grouped_basis(pts, wts, 1, beam.pressure_columns)
        _, dN = block.shape_functions(np.broadcast_to(xi[None, :, None], (E, S1, n)).ravel(),
                                      sec[..., 0].ravel(), sec[..., 1].ravel())
        self.G, det = el.reference_gradients(q0e, dN.reshape(E, S1 * n, *dN.shape[1:]))
        self.Wphi = (det.reshape(E, S1, n) * w)[..., None] * phi[:, :, :n]
        self.phi_sec, self.phi_ring, self.keep = phi[:, :, :n], phi[:, :, n:], keep

    def at(self, qe: np.ndarray) -> np.ndarray:
        """θ at the kept sample points for the elements' nodal vectors qe (E, S, 3)."""
        J = determinant(np.einsum("esi,epsj->epij", qe, self.G)).reshape(self.Wphi.shape[:3])
        M = np.matmul(np.swapaxes(self.Wphi, -1, -2), self.phi_sec)
        c = np.linalg.solve(M, np.einsum("etpk,etp->etk", self.Wphi, J))
        return np.einsum("etpk,etk->etp", self.phi_ring, c).reshape(-1)[self.keep]


def surface_cells(sampler: SurfaceSampler, q: np.ndarray) -> tuple:
    """(points, cells, point data) of the deformed surfaces for nodal vectors q (the cells are
    the same list at every call: ``VtkSeries`` then encodes them once)."""
    pts, quads, caps, data = sampler.mesh(q)
    if sampler.cell_blocks is None:
        sampler.cell_blocks = [("quad", quads)] + [("polygon", c[None, :]) for c in caps]
    return pts, sampler.cell_blocks, data


#: point fields that are no data to look at (ids, positions, the projection; ``history_*`` and
#: ``multiplier_*`` are a term's restart state and the multipliers)
NOT_DRAWN = ("id", "x", "x0", "projection", "area")


def contact_cells(fields: dict) -> tuple:
    """(points, cells, point data) of the contact points (``contact_reports.contact_fields``):
    every per-point field (gap, pressure, slip, a term's shear stress, ...), and the axial slip."""
    n = len(fields["x"])
    data = {k: np.asarray(v, dtype=float) for k, v in fields.items()       # not the restart state
            if k not in NOT_DRAWN and not k.startswith(("multiplier", HISTORY)) and len(v) == n}
    data["slip_axial"] = fields["slip"][:, 0]
    return fields["x"], [("vertex", np.arange(n)[:, None])], data


#: surface points from which ``output.vtk_compress: auto`` compresses a VTU: zlib makes the files
#: 0.42x the size but costs ~1.8 µs per point (85 % of the write: 6.7 against 1.0 ms for the
#: Achilles surface of 3 672 points), noticeable beside the ~50 ms a level of such a model
#: takes; from 20 000 points a level's solve takes seconds and the files' size matters more
AUTO_COMPRESS_POINTS = 20_000


#: a series' .pvd collection is rewritten with its first VTU, then at most this often [s] and at
#: the end (``write_indexes``): replacing a file costs ~3 ms on ext4 (it flushes a file renamed
#: over another), twice a level on a stride; the VTUs themselves are written at every level
INDEX_INTERVAL = 0.5


class VtkSeries:
    """VTU files ``<series>_NNNN.vtu`` and their ``<series>.pvd`` collections in one directory.
    A VTU is listed at its time (a load history's clock [s], else the load factor); one written
    without a time (a history's rest state) or at the time of the entry before it (a level passed
    over with the one before it: the same state) is not listed, so each time has one file."""

    def __init__(self, directory: str, compress: bool | None = None):
        self.dir = directory
        self.compress = compress                 # None: by size (AUTO_COMPRESS_POINTS)
        self.entries: dict[str, list[tuple[float, str]]] = {"surface": [], "contact": []}
        self._indexed: dict[str, float] = {}     # when each .pvd was last rewritten (monotonic)
        self._cells: dict[str, tuple] = {}       # per series: (cell blocks, compress, their XML)

    def write(self, series: str, k: int, t: float | None, pts, cells, data, field_data=None) -> int:
        """One VTU of a time series at time ``t`` (None: not listed) and, when due
        (``INDEX_INTERVAL``), its .pvd collection (binary, in single precision: for display,
        results.h5 keeps double; half the size and the write time), zlib-compressed if asked or,
        by default, from ``AUTO_COMPRESS_POINTS`` points on; ``field_data``: the level's values
        (``stable``, ...).  A failed write leaves no VTU and raises the OSError.  Returns the size."""
        name = f"{series}_{k:04d}.vtu"
        path = os.path.join(self.dir, name)
        with np.errstate(over="ignore"):            # beyond single precision: inf (results.h5: double)
            data = {key: np.asarray(v, dtype=np.float32) for key, v in data.items()}
        compress = self.compress if self.compress is not None else len(pts) >= AUTO_COMPRESS_POINTS
        listed = self._listed(series, t, name)
        try:
            write_vtu(path, np.asarray(pts, dtype=np.float32), cells, data, compress=bool(compress),
                      cells_text=self._cells_text(series, cells, bool(compress)), field_data=field_data)
            size = os.path.getsize(path)
            now = time.monotonic()
            if listed and now - self._indexed.get(series, -np.inf) >= INDEX_INTERVAL:
                self._write_index(series, self.entries[series] + listed)
                self._indexed[series] = now
        except OSError:
            remove_quietly(path)                   # never leave a truncated VTU behind
            raise
        self.entries[series] += listed
        return size

    def write_level(self, k: int, t: float | None, meshes: dict, field_data: dict) -> int:
        """Level ``k``'s VTU in each series of ``meshes`` ({series: (pts, cells, data)}), all or
        none: if one fails, the others are discarded and the OSError raised.  Returns the size."""
        try:
            return sum(self.write(series, k, t, *mesh, field_data=field_data)
                       for series, mesh in meshes.items())
        except OSError:
            self.discard(k)
            raise

    def discard(self, k: int) -> None:
        """Level ``k``'s VTUs removed from disk and from the collections (a level not kept)."""
        for series in self.entries:
            name = f"{series}_{k:04d}.vtu"
            self.entries[series] = [e for e in self.entries[series] if e[1] != name]
            remove_quietly(os.path.join(self.dir, name))

    def _listed(self, series: str, t: float | None, name: str) -> list[tuple[float, str]]:
        """The .pvd entry of a VTU at time ``t``: none without a time or at the last entry's time."""
        entries = self.entries[series]
        return [] if t is None or (entries and entries[-1][0] == t) else [(t, name)]

    def _cells_text(self, series: str, cells: list, compress: bool) -> str:
        """The ``<Cells>`` XML of ``cells``, encoded again only when the series' cell blocks are
        another list than last time (the surface's are one list for the whole run)."""
        kept = self._cells.get(series)
        if kept is None or kept[0] is not cells or kept[1] != compress:
            kept = self._cells[series] = (cells, compress, cells_xml(cells, compress))
        return kept[2]

    def write_indexes(self) -> str | None:
        """Every series' .pvd collection with all its files so far; None, or the one-line reason
        one could not be written."""
        for series, entries in self.entries.items():
            try:
                if entries:
                    self._write_index(series, entries)
            except OSError as exc:
                return f"{os.path.join(self.dir, series + '.pvd')}: cannot write: {os_reason(exc)}"
        return None

    def _write_index(self, series: str, entries: list) -> None:
        """The .pvd collection; an OSError names it (not the VTU being written, nor the temporary
        file: a folder named surface.pvd was reported as 'surface_0000.vtu: Is a directory')."""
        rows = "\n".join(f'    <DataSet timestep="{t:.10g}" part="0" file="{f}"/>' for t, f in entries)
        path = os.path.join(self.dir, f"{series}.pvd")
        try:
            atomic_write(path, '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                               f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n")
        except OSError as exc:
            raise OSError(exc.errno, exc.strerror, path) from None

    def resume(self, times: list[float | None], warnings: list | None = None) -> None:
        """Continue the series of a restarted run whose levels 0 … n are at ``times`` (``write``'s
        t): their files are listed again, the VTUs of later levels removed (``<series>_NNNN.vtu``
        only: other files and folders so named are a user's and stay).  ``warnings`` (the run's,
        when it writes VTUs) gets a note on the levels without one (solved with output.vtk off)."""
        for series in self.entries:
            for k in range(len(times)):
                if os.path.exists(os.path.join(self.dir, f"{series}_{k:04d}.vtu")):
                    self.entries[series] += self._listed(series, times[k], f"{series}_{k:04d}.vtu")
        ours = re.compile(f"({'|'.join(self.entries)})_([0-9]{{4,}})\\.vtu")
        for name in os.listdir(self.dir):
            match = ours.fullmatch(name)        # a run's VTU, not a user's surface_notes_7.txt
            if match and int(match.group(2)) >= len(times) and os.path.isfile(os.path.join(self.dir, name)):
                os.remove(os.path.join(self.dir, name))
        missing = [k for k in range(len(times)) if not os.path.exists(os.path.join(self.dir, f"surface_{k:04d}.vtu"))]
        note = (f"output.vtk: {len(missing)} state(s) before the restart ({missing[0]}-{missing[-1]}; 0 is the "
                "rest state) have no ParaView files (solved with output.vtk false, or removed): the .pvd "
                "series lacks them; results.h5 has their surfaces") if missing else ""
        if warnings is not None and note and note not in warnings:
            warnings.append(note)
