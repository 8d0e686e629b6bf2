"""The surface VTU's point fields (io/surface_fields.py): each field against its definition
written out here for a homogeneous deformation, where each applies, and the chart labels and
messages that read the registry."""
import numpy as np
import pytest

from ancf_petsc.io.surface_fields import SURFACE_FIELDS, SampledState, fields_for
from ancf_petsc.physics.goh import GOH
from ancf_petsc.physics.materials import NeoHookean
from ancf_petsc.viz.surface_mesh import SurfaceMesh, field_values

MU, K, K1, K2 = 1.0e6, 50.0e6, 2.0e6, 5.0
LAM = np.array([1.1, 0.97, 0.96])


def homogeneous(n=5, beam=2, fibres=True, seed=0):
    """n points of a body stretched by F = diag(LAM), fibres (if any) along x."""
    rng = np.random.default_rng(seed)
    r0 = rng.uniform(-1e-3, 1e-3, (n, 3))
    F = np.broadcast_to(np.diag(LAM), (n, 3, 3)).copy()
    law = GOH(MU, K, K1, K2).with_directions(np.tile([1.0, 0.0, 0.0], (1, n, 1))) if fibres else None
    return SampledState(r0 @ np.diag(LAM), r0, F, beam, law)


def test_each_field_against_its_definition():
    s = homogeneous()
    J = np.prod(LAM)
    # neo-Hookean matrix + the fibre term by hand: W_f = k1/(2 k2) (exp(k2 E^2) - 1), E = I4 - 1
    E = LAM[0] ** 2 - 1.0
    P_xx = NeoHookean(MU, K).stress(s.F[:1])[0][0, 0, 0] + K1 * E * np.exp(K2 * E * E) * 2.0 * LAM[0]
    expect = {"displacement": s.r - s.r0, "E_xx": 0.5 * (LAM[0] ** 2 - 1.0), "J": J, "beam": 2.0,
              "fibre_stretch": LAM[0], "fibre_stress": P_xx * LAM[0] / J}
    assert set(expect) == set(SURFACE_FIELDS)          # a new field needs its line here
    for name, f in SURFACE_FIELDS.items():
        v = f.values(s)
        assert v.shape == (5,) + ((3,) if f.components == 3 else ()), name
        assert np.allclose(v, expect[name], rtol=1e-12, atol=1e-15), name


def test_fields_are_written_where_they_apply():
    goh, plain = homogeneous(3, beam=0), homogeneous(4, beam=1, fibres=False)
    assert [f.name for f in fields_for([goh, plain])] == list(SURFACE_FIELDS)
    assert [f.name for f in fields_for([plain])] == ["displacement", "E_xx", "J", "beam"]
    fibre_only = {"fibre_stretch", "fibre_stress"}          # NaN on a beam without fibres
    for f in fields_for([goh, plain]):
        v = f.values(plain)
        assert np.all(np.isnan(v)) if f.name in fibre_only else np.all(np.isfinite(v)), f.name
        assert np.all(np.isfinite(f.values(goh))), f.name
    assert SURFACE_FIELDS["displacement"].values(plain).shape == (4, 3)


def _mesh(states):
    data = {f.name: np.concatenate([f.values(s) for s in states]) for f in fields_for(states)}
    pts = np.concatenate([s.r for s in states])
    return SurfaceMesh(pts, np.zeros((0, 4), dtype=int), [], data, "surface_0001.vtu")


def test_chart_labels_and_messages_read_the_registry():
    mesh = _mesh([homogeneous()])
    for name, f in SURFACE_FIELDS.items():
        v, label = field_values(mesh, name)
        assert label == f"{f.label} [{f.unit}]", name
        stored = mesh.point_data[name]
        assert np.allclose(v, f.factor * (np.linalg.norm(stored, axis=1) if stored.ndim == 2 else stored))
    assert field_values(mesh, "fibre_stress")[1].endswith("[MPa]")
    with pytest.raises(ValueError, match=r"color_by='fibre_stress'.*available: E_xx, J, beam, "
                                         r"displacement.*fibre_stress is written for fibre-reinforced "
                                         r"models .* only"):
        field_values(_mesh([homogeneous(fibres=False)]), "fibre_stress")
