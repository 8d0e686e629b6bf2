#!/usr/bin/env bash
# Idempotent install of the Debian packages that the 3D solids (ancf_verify, tests/solids, make
# verify-solid) need; scripts/setup.sh runs it last:
# FEniCSx/dolfinx 0.5.2 (built against the same PETSc 3.18 as petsc4py) and gmsh 4.8 with its Python
# API.  Quick when everything is present: it only asks dpkg, then checks that both import.
set -euo pipefail
cd "$(dirname "$0")/.."

DEB_PKGS=(python3-dolfinx python3-gmsh gmsh)
PY=.venv/bin/python
[ -x "$PY" ] || PY=/usr/bin/python3

missing=()
for p in "${DEB_PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup-solid] installing Debian packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! "$PY" -c "import dolfinx, dolfinx.fem.petsc, dolfinx.io.gmshio, gmsh" 2>/dev/null; then
  echo "[setup-solid] dolfinx/gmsh do not import; the error was:" >&2
  "$PY" -c "import dolfinx, dolfinx.fem.petsc, dolfinx.io.gmshio, gmsh" >&2 || true
  exit 1
fi
