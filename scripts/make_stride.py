"""Write the synthetic walking stride (ancf_petsc/workflows/stride.py) in its three biases to
configs/data/stride_walking_<bias>.csv, and the uniform one also as an OpenSim storage file."""
import sys

from ancf_petsc.workflows.stride import main

if __name__ == "__main__":
    sys.exit(main())
