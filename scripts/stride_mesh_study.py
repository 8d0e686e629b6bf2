"""How many elements the walking stride needs (issue 38): per contact law, the stride on a ladder of
meshes, frames per second against each output's error from the finest mesh (apps/stride_mesh.py).

    python scripts/stride_mesh_study.py --elements 2,4,8,16 --csv docs/gait_stride_mesh.csv \
        --figure docs/figures/stride_mesh.png
"""
import sys

from apps.stride_mesh import main

if __name__ == "__main__":
    sys.exit(main())
