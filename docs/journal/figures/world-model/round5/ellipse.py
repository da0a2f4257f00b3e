"""How often the truth lies inside the 2-sigma ellipse Carto's belief is drawn with.

Reads the twin's belief trace (RUST_LOG=twin::belief=trace, ANSI stripped) of one or more runs
and, at every MOVE_DONE sample where the filter has a covariance, computes the squared
Mahalanobis distance d2 = e' P^-1 e of the true error e = body - belief under the filter's
position covariance P. For a consistent filter d2 follows chi-square with 2 degrees of freedom:
86.5 % of samples inside the 2-sigma ellipse (d2 <= 4), 98.9 % inside 3 sigma (d2 <= 9).

usage: python3 ellipse.py LOG...
"""
import re
import sys

for path in sys.argv[1:]:
    d2s = []
    for line in open(path):
        if "belief against the truth" not in line or "move_done=true" not in line:
            continue
        f = dict(re.findall(r"(\w+)=([-\w.]+)", line))
        try:
            ex, ey = float(f["ex"]), float(f["ey"])
            a, b, c = float(f["sxx"]), float(f["sxy"]), float(f["syy"])
        except (KeyError, ValueError):
            continue
        det = a * c - b * b
        if not det > 0:
            continue
        d2s.append((c * ex * ex - 2 * b * ex * ey + a * ey * ey) / det)
    n = len(d2s)
    if n == 0:
        print(f"{path}: no samples")
        continue
    inside2 = sum(d <= 4 for d in d2s) / n
    inside3 = sum(d <= 9 for d in d2s) / n
    d2s.sort()
    print(f"{path}: {n} stops, inside 2 sigma {inside2:.1%} (consistent: 86.5 %), "
          f"inside 3 sigma {inside3:.1%} (98.9 %), median d2 {d2s[n // 2]:.2f} (1.39)")
