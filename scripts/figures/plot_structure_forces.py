#!/usr/bin/env python3
"""Plot the force histories of sph-slope's structure_forces.csv as an SVG (standard library only).

Usage: plot_structure_forces.py OUT/structure_forces.csv figure.svg [--component Fx] [--names a,b]

One line per structure: the chosen force component (default Fx, the horizontal force along the
section; the column's unit, N/m in 2D or N in 3D, is taken from its header) against time. Used for
docs/figures/sph/piles_middle_structure_forces.svg (docs/sph.md, "Loads on structures").
"""
import argparse
import csv
import math
import sys

COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"]


def nice_ticks(lo, hi, n=6):
    span = hi - lo if hi > lo else 1.0
    raw = span / n
    mag = 10 ** math.floor(math.log10(raw))
    step = min((m * mag for m in (1, 2, 2.5, 5, 10) if m * mag >= raw), default=10 * mag)
    t = math.ceil(lo / step) * step
    ticks = []
    while t <= hi + 1e-12 * span:
        ticks.append(round(t, 12))
        t += step
    return ticks


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("svg")
    ap.add_argument("--component", default="Fx", help="Fx, Fy, Fz, Mx, My or Mz (default Fx)")
    ap.add_argument("--names", default="", help="comma-separated structure names (default: all)")
    ap.add_argument("--title", default="")
    a = ap.parse_args()

    with open(a.csv, newline="") as f:
        rows = list(csv.reader(f))
    header, data = rows[0], [[float(v) for v in r] for r in rows[1:] if r]
    if header[0] != "time_s" or not data:
        sys.exit(f"{a.csv}: not a structure_forces.csv with data rows")
    wanted = [n for n in a.names.split(",") if n]
    series = []  # (name, unit, column)
    for k, h in enumerate(header[1:], start=1):
        name, _, rest = h.partition("_" + a.component + "_")
        if not rest or (wanted and name not in wanted):
            continue
        series.append((name, rest.replace("_per_", "/").replace("Nm", "N m"), k))
    if not series:
        sys.exit(f"{a.csv}: no column with component {a.component}" + (f" for {a.names}" if wanted else ""))
    t = [r[0] for r in data]
    lo = min(0.0, min(r[k] for r in data for _, _, k in series))
    hi = max(0.0, max(r[k] for r in data for _, _, k in series))
    if hi <= lo:
        hi = lo + 1.0
    W, H, ml, mr, mt, mb = 760, 440, 80, 150, 30, 55
    t0, t1 = t[0], max(t[-1], t[0] + 1e-12)

    def px(v):
        return ml + (v - t0) / (t1 - t0) * (W - ml - mr)

    def py(v):
        return H - mb - (v - lo) / (hi - lo) * (H - mt - mb)

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
           f'<rect width="{W}" height="{H}" fill="white"/>']
    for v in nice_ticks(lo, hi):
        out.append(f'<line x1="{ml}" y1="{py(v):.1f}" x2="{W - mr}" y2="{py(v):.1f}" stroke="#e0e0e0"/>')
        out.append(f'<text x="{ml - 6}" y="{py(v) + 4:.1f}" text-anchor="end">{v:g}</text>')
    for v in nice_ticks(t0, t1):
        out.append(f'<line x1="{px(v):.1f}" y1="{H - mb}" x2="{px(v):.1f}" y2="{H - mb + 5}" stroke="black"/>')
        out.append(f'<text x="{px(v):.1f}" y="{H - mb + 18}" text-anchor="middle">{v:g}</text>')
    out.append(f'<line x1="{ml}" y1="{py(0):.1f}" x2="{W - mr}" y2="{py(0):.1f}" stroke="#888"/>')
    out.append(f'<rect x="{ml}" y="{mt}" width="{W - ml - mr}" height="{H - mt - mb}" fill="none" stroke="black"/>')
    out.append(f'<text x="{(ml + W - mr) / 2}" y="{H - 12}" text-anchor="middle">time (s)</text>')
    unit = series[0][1]
    out.append(f'<text transform="translate(18,{(mt + H - mb) / 2}) rotate(-90)" text-anchor="middle">'
               f'{a.component} ({unit})</text>')
    if a.title:
        out.append(f'<text x="{(ml + W - mr) / 2}" y="18" text-anchor="middle">{a.title}</text>')
    for q, (name, _, k) in enumerate(series):
        c = COLOURS[q % len(COLOURS)]
        pts = " ".join(f"{px(r[0]):.1f},{py(r[k]):.1f}" for r in data)
        out.append(f'<polyline points="{pts}" fill="none" stroke="{c}" stroke-width="1.8"/>')
        y = mt + 14 + 18 * q
        out.append(f'<line x1="{W - mr + 10}" y1="{y - 4}" x2="{W - mr + 30}" y2="{y - 4}" stroke="{c}" stroke-width="2"/>')
        out.append(f'<text x="{W - mr + 36}" y="{y}">{name}</text>')
    out.append("</svg>")
    with open(a.svg, "w") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
