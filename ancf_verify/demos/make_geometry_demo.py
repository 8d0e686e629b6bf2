"""Make the worked example of docs/geometry.md: a small labelled mask of a three-subtendon tendon
section (no downloads), a two-slice NIfTI label volume of the same tendon tapering and rotating
along its length, and the figure of the extracted outlines over the mask.

    .venv/bin/python scripts/make_geometry_demo.py [--out configs/data] [--figure docs/figures/geometry_demo_outlines.png]

The section is synthetic but built like a segmentation: a bean-shaped tendon of about 25 mm^2
split into three subtendons (labels 1 soleus, 2 medial, 3 lateral gastrocnemius) by curved
borders meeting at one point, a one-pixel background gap along part of one border (as manual
segmentations leave), and one stray pixel of label 2 away from its region (speckle).  Pixel
size 0.05 mm; the image is 150 x 110 pixels.  Everything is deterministic (no random numbers).
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np

from ancf_verify import paths

ROOT = paths.ROOT

PIXEL_MM = 0.05
SHAPE = (110, 150)                 # rows, columns
NAMES = {1: "soleus", 2: "medial_gastrocnemius", 3: "lateral_gastrocnemius"}


def labels(s: float = 0.0) -> np.ndarray:
    """Label image of the section at fraction s of the tendon (0: the PNG; 1: the far slice):
    the far section is 20 % smaller and turned by 25 degrees."""
    rows, cols = np.mgrid[0:SHAPE[0], 0:SHAPE[1]].astype(float)
    y = (cols - (SHAPE[1] - 1) / 2) * PIXEL_MM            # image axes: columns right = y,
    z = -(rows - (SHAPE[0] - 1) / 2) * PIXEL_MM           # rows down = -z
    scale, rot = 1.0 - 0.2 * s, np.deg2rad(25.0 * s)
    Y = (np.cos(rot) * y + np.sin(rot) * z) / scale
    Z = (-np.sin(rot) * y + np.cos(rot) * z) / scale
    inside = (Y / 3.3) ** 2 + (Z / 2.2) ** 2 * (1.0 + 0.25 * Y / 3.3) - 0.12 * np.exp(-(Y / 0.8) ** 2) * (Z > 0) <= 1.0
    ty, tz = 0.35, -0.25                                   # where the three borders meet
    rho = np.hypot(Y - ty, Z - tz)
    phi = np.degrees(np.arctan2(Z - tz, Y - ty)) % 360.0
    b1 = 95.0 + 12.0 * np.sin(rho / 1.2)                   # soleus | medial (curved)
    b2 = 212.0 - 6.0 * rho                                 # medial | lateral
    b3 = 330.0 + 8.0 * np.sin(rho / 0.9)                   # lateral | soleus
    lab = np.where((phi >= b1) & (phi < b2), 2, np.where((phi >= b2) & (phi < b3), 3, 1))
    lab = np.where(inside, lab, 0)
    if s == 0.0:
        # a one-pixel background gap along the outer part of the soleus | medial border
        gap = (np.abs(phi - b1) * np.pi / 180.0 * rho < 0.6 * PIXEL_MM) & (rho > 1.3)
        lab[gap & inside] = 0
        lab[5, 10] = 2                                     # a stray pixel (speckle)
    return lab.astype(np.uint8)


def write_png(path: str) -> None:
    from PIL import Image
    Image.fromarray(labels(0.0), mode="L").save(path)


def write_nifti(path: str) -> None:
    import nibabel as nib
    vol = np.stack([labels(0.0).T, labels(1.0).T], axis=2)       # (u = column, v = row, slice)
    img = nib.Nifti1Image(vol, np.diag([PIXEL_MM, PIXEL_MM, 40.0, 1.0]))
    img.header.set_xyzt_units("mm")
    img.header.set_data_dtype(np.uint8)
    nib.save(img, path)


def figure(config: str, out_png: str, mask: str) -> None:
    """Extracted outlines (splines), interfaces and junctions over the mask."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image

    from ancf_petsc.config.parse import load_config
    from ancf_petsc.geometry_input.tendon import build_tendon

    spec = load_config(config)
    tendon = build_tendon(spec.sections)
    st = tendon.stations[0][1]
    lab = np.array(Image.open(mask))
    h, w = lab.shape
    p = PIXEL_MM
    ext = [-0.5 * p, (w - 0.5) * p, -(h - 0.5) * p, 0.5 * p]     # y right, z up (image axes)
    fig, ax = plt.subplots(figsize=(7.5, 6.2))
    cmap = matplotlib.colors.ListedColormap(["#ffffff", "#c6dbef", "#fdd0a2", "#c7e9c0"])
    ax.imshow(lab, cmap=cmap, vmin=0, vmax=3, extent=ext, interpolation="nearest")
    shared = {}
    for name, loop in st.loops.items():
        for cv, _ in loop:
            shared.setdefault(id(cv), (cv, set()))[1].add(name)
    for cv, who in shared.values():
        S = cv.sample(16) * 1e3
        if len(who) > 1:
            ax.plot(S[:, 0], S[:, 1], "-", color="#b2182b", lw=2.2, zorder=3)
        else:
            ax.plot(S[:, 0], S[:, 1], "-", color="#2166ac", lw=1.4, zorder=3)
        ax.plot(cv.points[:, 0] * 1e3, cv.points[:, 1] * 1e3, ".", color="k", ms=3, zorder=4)
    J = st.junctions * 1e3
    ax.plot(J[:, 0], J[:, 1], "o", mfc="none", mec="k", ms=8, mew=1.4, zorder=5)
    for name, loop in st.loops.items():
        P = st.polyline(name)
        from ancf_petsc.geometry_input.polyline import centroid
        c = centroid(P) * 1e3
        ax.text(c[0], c[1], f"{name}\n{st.area[name] * 1e6:.2f} mm$^2$", ha="center", va="center", fontsize=8)
    ax.plot([], [], "-", color="#2166ac", label="free surface (spline)")
    ax.plot([], [], "-", color="#b2182b", lw=2.2, label="merged interface (one curve, both loops)")
    ax.plot([], [], ".", color="k", label="spline control points")
    ax.plot([], [], "o", mfc="none", mec="k", label="junctions")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, fontsize=8, frameon=False)
    ax.set_xlabel("y [mm] (image columns)")
    ax.set_ylabel("z [mm] (image rows, upwards)")
    ax.set_title("Outlines extracted from the label mask (scripts/make_geometry_demo.py)", fontsize=10)
    ax.set_aspect("equal")
    fig.tight_layout()
    fig.savefig(out_png, dpi=130)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], allow_abbrev=False)
    ap.add_argument("--out", default=os.path.join(ROOT, "configs", "data"))
    ap.add_argument("--figure", default=os.path.join(ROOT, "docs", "figures", "geometry_demo_outlines.png"))
    ap.add_argument("--no-figure", action="store_true")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    png = os.path.join(args.out, "demo_tendon_labels.png")
    nii = os.path.join(args.out, "demo_tendon_labels.nii.gz")
    write_png(png)
    write_nifti(nii)
    print(f"wrote {png} and {nii}")
    if not args.no_figure:
        figure(os.path.join(ROOT, "configs", "geometry_mask_demo.yaml"), args.figure, png)
        print(f"wrote {args.figure}")
    return 0
