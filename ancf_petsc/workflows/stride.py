"""A synthetic walking stride of the three triceps-surae muscles, for the gait examples and tests.

Not measured data.  The total Achilles tendon force over one stride (100 frames, 1 s) is shaped
like published walking profiles: a mid-stance bump (the soleus braking the shank's forward
rotation) and the push-off peak late in stance, then nearly nothing in swing (toe-off at 62 % of
the cycle); it is scaled to a 2.63 kN peak (walking, Kharazi et al., Sci. Rep. 11 (2021)).  Each
muscle has its own curve, so the loads are not proportional: the soleus rises earlier in stance,
the gastrocnemii peak later at push-off.  The shares of the three muscles at their peaks follow
the loading biases of Blank et al. (2024): gastrocnemius-biased 20/40/40 %, uniform, and
soleus-biased 60/20/20 % (soleus / medial / lateral gastrocnemius).
"""
from __future__ import annotations

import numpy as np

from .envelope import BIASES

#: OpenSim's muscle names in the Rajagopal et al. (2016) full-body model (right leg)
OPENSIM_COLUMNS = ("soleus_r", "gasmed_r", "gaslat_r")
#: (mid-stance bump: centre, width, height; push-off peak: centre, width) per muscle, in stride share
SHAPES = {"soleus_r": (0.20, 0.08, 0.45, 0.46, 0.07),
          "gasmed_r": (0.25, 0.07, 0.25, 0.49, 0.06),
          "gaslat_r": (0.25, 0.07, 0.25, 0.49, 0.06)}
TOE_OFF = 0.62
SWING_LEVEL = 0.01          # passive force in swing, as a share of each muscle's peak
PEAK_N = 2630.0


def _muscle_curve(s: np.ndarray, shape: tuple) -> np.ndarray:
    """One muscle's force over stride share s, peak 1 (the push-off peak)."""
    c1, w1, h1, c2, w2 = shape
    f = h1 * np.exp(-((s - c1) / w1) ** 2) + np.exp(-((s - c2) / w2) ** 2)
    swing = 0.5 * (1.0 + np.tanh((s - TOE_OFF) / 0.015))       # smooth toe-off
    f = (1.0 - swing) * f + swing * SWING_LEVEL
    return np.maximum(f, SWING_LEVEL) / f.max()


def synthetic_stride(bias: str, frames: int = 100, duration: float = 1.0,
                     peak: float = PEAK_N) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Times [s] and the force [N] of each muscle (OpenSim names) over one stride, the muscles
    weighted by the ``bias`` (envelope.BIASES) and the total scaled to ``peak`` [N]."""
    s = np.arange(frames) / frames
    forces = {m: w * _muscle_curve(s, SHAPES[m]) for m, w in zip(OPENSIM_COLUMNS, BIASES[bias])}
    total = sum(forces.values())
    scale = peak / total.max()
    return s * duration, {m: f * scale for m, f in forces.items()}


def write_csv(path: str, times: np.ndarray, forces: dict[str, np.ndarray], note: str) -> None:
    """A CSV with a '#' comment, a header line and one row per frame (time [s], forces [N])."""
    with open(path, "w") as fh:
        for line in note.splitlines():
            fh.write(f"# {line}\n")
        fh.write(",".join(["time"] + list(forces)) + "\n")
        for k, t in enumerate(times):
            fh.write(",".join([f"{t:.4f}"] + [f"{f[k]:.3f}" for f in forces.values()]) + "\n")


def write_storage(path: str, times: np.ndarray, forces: dict[str, np.ndarray], name: str) -> None:
    """An OpenSim storage file (version 1, as static optimisation writes its forces)."""
    with open(path, "w") as fh:
        fh.write(f"{name}\nversion=1\nnRows={len(times)}\nnColumns={len(forces) + 1}\n"
                 "inDegrees=no\nendheader\n")
        fh.write("\t".join(["time"] + list(forces)) + "\n")
        for k, t in enumerate(times):
            fh.write("\t".join([f"{t:.4f}"] + [f"{f[k]:.3f}" for f in forces.values()]) + "\n")


def write_stride_files(directory: str) -> list[str]:
    """The stride in its three biases as CSV files (stride_walking_<bias>.csv) and the uniform
    one also as OpenSim storage (stride_walking_uniform.sto) in ``directory``; their paths."""
    import os
    out = []
    for bias in BIASES:
        times, forces = synthetic_stride(bias)
        note = (f"Synthetic walking stride, {bias}-biased (not measured data): muscle forces [N] over 100 "
                "frames of a 1 s stride,\ntotal peak 2.63 kN; made by scripts/make_stride.py "
                "(ancf_petsc/workflows/stride.py says how).")
        out.append(os.path.join(directory, f"stride_walking_{bias}.csv"))
        write_csv(out[-1], times, forces, note)
        if bias == "uniform":
            out.append(os.path.join(directory, "stride_walking_uniform.sto"))
            write_storage(out[-1], times, forces,
                          "synthetic_walking_stride_uniform (ancf-petsc scripts/make_stride.py; not measured)")
    return out


def main(argv: list[str] | None = None) -> int:
    """scripts/make_stride.py: ``write_stride_files`` into ``--out`` (default configs/data)."""
    import argparse
    from .envelope import DATA
    ap = argparse.ArgumentParser(prog="make_stride.py", allow_abbrev=False, description=(
        "Write the synthetic walking stride in its three biases to stride_walking_<bias>.csv, and "
        "the uniform one also as an OpenSim storage file (ancf_petsc/workflows/stride.py says how)."))
    ap.add_argument("--out", default=DATA, help="directory (default: %(default)s)")
    for path in write_stride_files(ap.parse_args(argv).out):
        print(path)
    return 0
