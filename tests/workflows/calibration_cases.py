"""Small calibration cases for the tests: a one-element neo-Hookean bar in tension (about 10 ms a
solve), its data files and fit files, written into a test's directory."""
from __future__ import annotations

import os

import numpy as np
import yaml

from helpers import CONFIGS

#: the bar of the small twin (configs/calibration_bar.yaml): K / mu = 3 (compressible), so that
#: elongation and lateral contraction together determine both moduli
BAR = {k: v for k, v in yaml.safe_load(open(os.path.join(CONFIGS, "calibration_bar.yaml"))).items()
       if k not in ("output", "units")}
#: the small twin's fit file (mu and K from elongation and lateral stretch)
BAR_TWIN = os.path.join(CONFIGS, "fits", "bar_twin.yaml")
LEVELS = [0.1 * k for k in range(1, 11)]
TRUE = (1.2e6, 3.6e6)


def write_yaml(path, doc) -> str:
    with open(path, "w") as fh:
        yaml.safe_dump(doc, fh, sort_keys=False)
    return str(path)


def write_bar(directory, **material) -> str:
    doc = {**BAR, "beams": [dict(BAR["beams"][0], material={**BAR["beams"][0]["material"], **material})]}
    return write_yaml(os.path.join(directory, "bar.yaml"), doc)


def write_csv(path, columns: dict) -> str:
    names = list(columns)
    with open(path, "w") as fh:
        fh.write("# written by the tests\n" + ",".join(names) + "\n")
        for row in zip(*columns.values()):
            fh.write(",".join(repr(float(x)) for x in row) + "\n")
    return str(path)


def write_fit(directory, parameters: list, data: list, **extra) -> str:
    doc = {"model": "bar.yaml", "parameters": parameters, "data": data, "output": "out", **extra}
    return write_yaml(os.path.join(directory, "fit.yaml"), doc)


MU = {"key": "beams[0].material.mu", "name": "mu", "bounds": [2.0e5, 1.0e7], "log": True, "start": 2.0e6}
K = {"key": "beams[0].material.bulk_modulus", "name": "K", "bounds": [1.0e6, 1.0e9], "log": True, "start": 5.0e6}


def bar_case(directory, parameters=(MU, K), lateral: bool = True, **extra) -> str:
    """The bar, a placeholder data file (the twin writes its values) and a fit file."""
    write_bar(directory)
    n = len(LEVELS)
    write_csv(os.path.join(directory, "data.csv"), {"level": LEVELS, "u_mm": np.linspace(1, 20, n),
                                                   "ry": -np.linspace(0.01, 0.1, n)})
    data = [{"name": "elongation", "file": "data.csv", "load": "level", "value": "u_mm",
             "value_scale": 1e-3, "sigma": 5e-5, "quantity": "elongation", "probe": "tip"}]
    if lateral:
        data.append({"name": "lateral", "file": "data.csv", "load": "level", "value": "ry",
                     "sigma": 5e-4, "quantity": "probe", "probe": "tip_ry", "component": "y"})
    return write_fit(directory, list(parameters), data, **extra)
