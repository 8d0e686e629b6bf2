"""The 3D-solid tests need dolfinx and gmsh (Debian, scripts/setup_solid.sh, run by make test's
setup); without them every test here is skipped with one line naming the missing package
(``pytest -rs``, as make test runs it)."""
import importlib.util

import pytest

MISSING = [name for name in ("gmsh", "ufl", "dolfinx") if importlib.util.find_spec(name) is None]


def pytest_collection_modifyitems(config, items):
    if not MISSING:
        return
    skip = pytest.mark.skip(reason=f"3D-solid tests: {', '.join(MISSING)} not importable; "
                                   "install with: bash scripts/setup_solid.sh")
    for item in items:
        if "tests/solids/" in str(item.fspath).replace("\\", "/"):
            item.add_marker(skip)


@pytest.fixture(scope="session")
def solid_stack():
    """MPI/PETSc, then gmsh, ufl and dolfinx (ancf_verify.stack)."""
    from ancf_verify.stack import import_stack
    import_stack()
