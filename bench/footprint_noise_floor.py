#!/usr/bin/env python3
"""The footprint's noise floor of the Alplehner calibration case (docs/calibration.md, "How close to
perfect"): the Dice score T (Tversky, alpha = beta = 1/2) of the footprint (peak depth > 0.1 m) of
runs with mu or xi changed by small relative amounts, against the footprint of the truth itself
(Voellmy mu = 0.155, xi = 4000 m/s^2, h0 = 0.25 m, release 1 m, one thread). Prints, never asserts.

  PYTHONPATH=build/python python3 bench/footprint_noise_floor.py [--d0 10] [--changes mu:1e-9,mu:1e-3,xi:1e-3]

Needs the Python module (scripts/build builds it) and NumPy. About 10 s per run at d0 = 10 m and
40 s at d0 = 5 m on one core.
"""
import argparse
from pathlib import Path

import numpy as np

import geohaz

root = Path(__file__).resolve().parents[1]
data = root / "data" / "terrain" / "alr"
ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("--d0", type=float, default=10.0, help="particle spacing (m)")
ap.add_argument("--changes", default="mu:1e-9,mu:2e-9,mu:1e-6,mu:1e-4,mu:1e-3,mu:1e-2,xi:1e-3,xi:7e-3",
                help="comma-separated parameter:relative change")
a = ap.parse_args()


def footprint(mu, xi):
    r = geohaz.runout.run(str(data / "avaAlr.tif"), release=str(data / "relAlr.shp"), particles=False, threads=1,
                          set={"model.friction": "voellmy", "model.mu": mu, "model.xi": xi, "model.d0": a.d0,
                               "model.h0": 0.25, "run.duration": 400.0, "release.depth": 1.0})
    return np.nan_to_num(r["maps"]["max_depth"]) > 0.1


truth = footprint(0.155, 4000.0)
print(f"d0 = {a.d0:g} m: the truth's footprint has {truth.sum()} cells", flush=True)
for change in a.changes.split(","):
    key, eps = change.split(":")
    eps = float(eps)
    f = footprint(0.155 * (1 + eps) if key == "mu" else 0.155, 4000.0 * (1 + eps) if key == "xi" else 4000.0)
    tp, fp, fn = (truth & f).sum(), (f & ~truth).sum(), (truth & ~f).sum()
    print(f"{key} x (1 + {eps:g}): T {tp / (tp + 0.5 * fp + 0.5 * fn):.4f} (FP {fp} cells, FN {fn})", flush=True)
