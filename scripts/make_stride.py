"""Write the synthetic walking stride (ancf_petsc/workflows/stride.py) in its three biases:
configs/data/stride_walking_<bias>.csv, and the uniform one as an OpenSim storage file
configs/data/stride_walking_uniform.sto."""
from __future__ import annotations

import os
import sys

from ancf_petsc.workflows.envelope import BIASES
from ancf_petsc.workflows.stride import synthetic_stride, write_csv, write_storage

HERE = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "configs", "data")


def main() -> int:
    for bias in BIASES:
        times, forces = synthetic_stride(bias)
        note = (f"Synthetic walking stride, {bias}-biased (not measured data): muscle forces [N] over 100 "
                "frames of a 1 s stride,\ntotal peak 2.63 kN; made by scripts/make_stride.py "
                "(ancf_petsc/workflows/stride.py says how).")
        write_csv(os.path.join(HERE, f"stride_walking_{bias}.csv"), times, forces, note)
        if bias == "uniform":
            write_storage(os.path.join(HERE, "stride_walking_uniform.sto"), times, forces,
                          "synthetic_walking_stride_uniform (ancf-petsc scripts/make_stride.py; not measured)")
    print(f"written to {HERE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
