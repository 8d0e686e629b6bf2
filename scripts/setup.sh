#!/usr/bin/env bash
# Idempotent bootstrap for a Debian 12 machine (run as root, or with sudo available).
#  1. Debian packages compiled against PETSc 3.18: petsc4py, mpi4py, h5py-mpi, OpenMPI, OpenBLAS.
#  2. A venv at .venv made by /usr/bin/python3 --system-site-packages for the PyPI parts.
#  3. `pip install -e .` (meshio, pymetis) with numpy pinned to Debian's build.
# Quick when everything is present: each step checks before it acts.
set -euo pipefail
cd "$(dirname "$0")/.."

DEB_PKGS=(python3-petsc4py python3-mpi4py python3-h5py-mpi openmpi-bin libopenmpi-dev
          libpetsc-real3.18-dev libopenblas0-pthread python3-numpy python3-scipy
          python3-matplotlib python3-yaml python3-pytest python3-pytest-xdist python3-venv
          python3-dev python3-pip python3-skimage python3-nibabel python3-svgelements python3-pil cython3)
# python3-pytest-xdist: make test's parallel workers; skimage, nibabel, svgelements, pil: geometry
# importers (label masks, NIfTI volumes, SVG paths; imported lazily); cython3: the compiled kernels
# (scripts/build_native.py)

missing=()
for p in "${DEB_PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] installing Debian packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if [ ! -x .venv/bin/python ]; then
  echo "[setup] creating .venv (system site packages)"
  /usr/bin/python3 -m venv --system-site-packages .venv
fi

stamp=.venv/.ancf-installed
if [ ! -f "$stamp" ] || [ setup.py -nt "$stamp" ] || [ scripts/constraints.txt -nt "$stamp" ]; then
  echo "[setup] pip install -e . (PyPI parts)"
  .venv/bin/python -m pip install -q --disable-pip-version-check -c scripts/constraints.txt -e . 
  touch "$stamp"
fi

# console scripts that import their entry point directly (what pip writes for a wheel): the
# ones `pip install -e` writes for a setup.py find it through importlib.metadata, which reads the
# metadata of every package on sys.path (Debian's dist-packages too): 50-90 ms of every
# ancf-solve's start-up.  Rewritten only when they differ (idempotent, quick).
.venv/bin/python - <<'EOF'
import os, re
text = open("setup.py").read()
for name, target in re.findall(r'"(ancf-[a-z]+)=([A-Za-z_.]+:[A-Za-z_]+)"', text):
    module, func = target.split(":")
    path = os.path.join(".venv", "bin", name)
    script = (f"#!{os.path.abspath('.venv/bin/python')}\n"
              f"# ancf-petsc console script (scripts/setup.sh): imports {target} directly\n"
              f"import sys\nfrom {module} import {func}\n\n"
              f"if __name__ == \"__main__\":\n    sys.exit({func}())\n")
    if not os.path.exists(path) or open(path).read() != script:
        with open(path, "w") as fh:
            fh.write(script)
        os.chmod(path, 0o755)
EOF

# the compiled kernels (Cython, in place; rebuilt only when a .pyx changed): without them the
# numpy kernels run, and ancf_petsc.native says so
.venv/bin/python scripts/build_native.py || echo "[setup] the compiled kernels are not built: the numpy kernels run instead" >&2

# byte-compile the package (what a non-editable install does): with PYTHONDONTWRITEBYTECODE set,
# as on CI, Python would otherwise compile every module at every start (90 ms of an Achilles
# column); quick when nothing changed, and a stale .pyc is ignored by Python, never used
.venv/bin/python -m compileall -q ancf_petsc ancf_verify apps >/dev/null

# the 3D-solid references (ancf_verify, tests/solids): dolfinx and gmsh from Debian; quick when
# present.  Without them make test still runs and names the missing package in its skip lines.
bash scripts/setup_solid.sh || echo "[setup] dolfinx/gmsh are not installed: the 3D-solid tests will be skipped" >&2
