"""ancf-petsc: PETSc-parallel ANCF continuum-beam solver for tendon mechanics."""
from setuptools import find_packages, setup

setup(
    name="ancf-petsc",
    version="0.1.0",
    description="ANCF 3363 continuum beams with arbitrary pretwisted sections, neo-Hookean "
                "material and sliding contact, assembled and solved with PETSc (SNES).",
    packages=find_packages(include=["ancf_petsc", "ancf_petsc.*", "ancf_verify", "ancf_verify.*", "apps"]),
    python_requires=">=3.11",
    # petsc4py, mpi4py, h5py (MPI build), numpy, scipy, matplotlib, PyYAML come from Debian
    # (scripts/setup.sh); only the pure-Python / self-contained parts come from PyPI.
    install_requires=["meshio>=5.3", "pymetis>=2023.1"],
    entry_points={
        "console_scripts": [
            "ancf-solve=apps.ancf_solve:cli",
            "ancf-report=apps.ancf_report:main",
            "ancf-sweep=apps.ancf_sweep:main",
            "ancf-study=apps.ancf_study:main",
            "ancf-fit=apps.ancf_fit:cli",
        ]
    },
)
