"""The tendon mesh refined around one interface (ancf_verify.contact.mesh.LocalSize, issue 41):
the size law, and a coarse mesh whose elements at the soleus-medial interface are finer than the
bulk while the far interfaces keep the bulk size, the shared curve meshed alike on both sides.
Seconds."""
import numpy as np
import pytest


@pytest.fixture(scope="module")
def secs(solid_stack):
    from ancf_verify.contact.tendon import tendon_sections
    return tendon_sections()


def test_the_size_is_local_then_grows_to_the_bulk():
    from ancf_verify.contact.mesh import LocalSize
    loc = LocalSize("mg_sol", 1e-3)
    line = np.array([[0.0, 0.0], [0.0, 0.01]])
    d = np.array([0.0, 1e-3, 2e-3, 4e-3, 6e-3, 1.0])
    s = loc.sizes(np.column_stack([d, np.full_like(d, 5e-3)]), line, 3e-3)
    assert s == pytest.approx([1e-3, 1e-3, 1e-3, 2e-3, 3e-3, 3e-3])
    assert loc.label() == "1.00 mm at mg_sol"


def _edges(msh, ft, tag):
    """The element size in the section on the facets with tag ``tag`` (their mean largest
    vertex-to-vertex extent in the (y, z) plane; psi = 0: the layers are straight) and their count."""
    from dolfinx import cpp
    facets = ft.indices[ft.values == tag]
    f2v = cpp.mesh.entities_to_geometry(msh._mesh, 2, facets, False)[:, :3]
    x = msh.geometry.x[f2v][:, :, 1:]
    e = np.linalg.norm(x - np.roll(x, 1, axis=1), axis=2)
    return float(e.max(axis=1).mean()), len(facets)


def test_a_mesh_refined_at_mg_sol(secs):
    from ancf_verify.contact.mesh import LocalSize, interface_tag, tendon_mesh
    h, hi = 4e-3, 1e-3
    uni = tendon_mesh(secs, h, 0.0)
    msh, ct, ft = tendon_mesh(secs, h, 0.0, local=LocalSize("mg_sol", hi))
    assert msh.topology.index_map(3).size_local > 2 * uni[0].topology.index_map(3).size_local
    sol, med = _edges(msh, ft, interface_tag(secs, 0, "mg_sol")), _edges(msh, ft, interface_tag(secs, 1, "mg_sol"))
    assert sol[1] == med[1]                        # the shared curve meshed alike on both sides
    assert sol[0] <= hi and med[0] <= hi
    assert _edges(uni[0], uni[2], interface_tag(secs, 0, "mg_sol"))[0] > 1.5 * hi
    # the lateral's outer face, mostly 2-6 mm from mg_sol: coarser than the interface
    assert _edges(msh, ft, interface_tag(secs, 2, "lg_outer"))[0] > 1.5 * sol[0]
