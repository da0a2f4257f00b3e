"""Sideways drift of Carto's dead reckoning per straight move, from the twin's belief trace.

Run a scenario with the trace on, strip the colours, then this script over the logs:
    RUST_LOG=twin::belief=trace explobot run ROOM.ron --seed S --quiet 2> run.log
    sed -i 's/\\x1b\\[[0-9;]*m//g' run.log
    python3 drift.py 'run*.log'
A straight move is two MOVE_DONE samples with the body's heading within 5 degrees and 0.3-0.6 m
apart; its drift is the change of the belief's error across the body between them.
"""
import glob, math, re, sys

def num(key, line):
    return float(re.search(key + r'=([-0-9.e]+)', line).group(1))

deltas = []
for path in sorted(glob.glob(sys.argv[1])):
    prev = None
    for line in open(path):
        if 'move_done=true' not in line:
            continue
        th, across, bx, by = (num(k, line) for k in ('th', 'e_across', 'bx', 'by'))
        if prev:
            turned = math.atan2(math.sin(th - prev[0]), math.cos(th - prev[0]))
            moved = math.hypot(bx - prev[2], by - prev[3])
            if abs(turned) < math.radians(5) and 0.3 < moved < 0.6:
                deltas.append((across - prev[1], moved))
        prev = (th, across, bx, by)
n = len(deltas)
if n == 0:
    sys.exit('no straight moves found')
rms = math.sqrt(sum(d * d for d, _ in deltas) / n)
length = sum(m for _, m in deltas) / n
xs = sorted(abs(d) for d, _ in deltas)
print(f'{n} straight moves, mean length {length:.3f} m: sideways drift rms {rms * 1000:.2f} mm '
      f'({rms / length * 100:.2f} % of the distance); |drift| percentiles 50/75/90/95/99 in mm:',
      [round(1000 * xs[int(p * (n - 1))], 2) for p in (0.5, 0.75, 0.9, 0.95, 0.99)])
