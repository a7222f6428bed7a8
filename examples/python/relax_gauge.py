"""Relax a knit and read its gauge: the five lines a designer needs.

    /usr/bin/python3 examples/python/relax_gauge.py [PATTERN_OR_CHART] [ROWS] [COLS]

PATTERN_OR_CHART: a built-in pattern (stockinette, garter, rib2x2, seed, …) or a chart
file such as tests/data/patterns/rib_and_seed.chart (the chart format: docs/patterns.md);
default stockinette, 12 × 12.
"""
import sys

import knitsim

pattern = sys.argv[1] if len(sys.argv) > 1 else "stockinette"
rows, cols = (int(a) for a in sys.argv[2:4]) if len(sys.argv) > 3 else (12, 12)

knit = knitsim.relax(pattern, rows=rows, cols=cols, max_time=0.5)
shape = knit.shape
print(f"{pattern} {rows}×{cols}: {knit.status} after {knit.state.time:.2f} s simulated")
print(f"  {10 / shape['stitch_width_cm']:.1f} stitches and "
      f"{10 / shape['row_height_cm']:.1f} rows per 10 cm")
print(f"  {shape['course_extent_cm']:.2f} cm wide, {shape['wale_extent_cm']:.2f} cm high, "
      f"edge curl {shape['edge_curl']:.2f} stitch widths")
