#!/usr/bin/env python3
"""Side-by-side peak maps of runs on one DTM (the figures of docs/validation/runout.md, "Against
AvaFrame com1DFA"). Not part of the build or the tests: it needs Debian's python3-rasterio and
python3-matplotlib, and the other tool's rasters (see ../shared/peers/avaframe/README.md for how
com1DFA is run beside geohaz).

    compare_peak_maps.py OUT.png DTM.tif {thickness|speed} TITLE RASTER [TITLE RASTER ...]

thickness: peak flow thickness (m, log colour scale 0.1-20 m, cells > 0.1 m);
speed: peak speed (m/s, 0-80, cells > 0.5 m/s). The hillshade is drawn from the DTM.
"""
import sys

import matplotlib
import numpy as np
import rasterio

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402

out, dtm, kind = sys.argv[1:4]
items = sys.argv[4:]
with rasterio.open(dtm) as f:
    z = f.read(1).astype(float)
    nodata = f.nodata
if nodata is not None:
    z[z == nodata] = np.nan
gy, gx = np.gradient(z, 5.0)
shade = np.cos(np.arctan(np.hypot(gx, gy)))
n = len(items) // 2
fig, axes = plt.subplots(1, n, figsize=(3.2 * n, 6.4))
axes = np.atleast_1d(axes)
for k in range(n):
    title, path = items[2 * k], items[2 * k + 1]
    with rasterio.open(path) as f:
        v = f.read(1).astype(float)
    if kind == "thickness":
        v[(v <= 0.1) | (v < -1000)] = np.nan
        im = axes[k].imshow(v, cmap="viridis", norm=LogNorm(0.1, 20), zorder=1)
        label = "peak flow thickness (m)"
    else:
        v[(v <= 0.5) | (v < -1000)] = np.nan
        im = axes[k].imshow(v, cmap="magma", vmin=0, vmax=80, zorder=1)
        label = "peak speed (m/s)"
    axes[k].imshow(shade, cmap="gray", zorder=0)
    axes[k].set_title(f"{title}\nmax {np.nanmax(v):.1f}", fontsize=9)
    axes[k].set_xticks([])
    axes[k].set_yticks([])
    axes[k].set_xlim(0, z.shape[1])
    axes[k].set_ylim(z.shape[0] * 0.72, 0)
fig.colorbar(im, ax=axes, shrink=0.6, label=label)
fig.savefig(out, dpi=75, bbox_inches="tight")
