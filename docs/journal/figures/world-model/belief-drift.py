"""Round 12: where Carto's belief goes wrong with the room known, from the twin's belief trace.

Run rooms with the trace and the pilot's corrections on, strip the colours, then this script:
    RUST_LOG=info,twin::belief=trace,carto::control::pilot::localisation=debug \\
        explobot run ROOM.ron --known-room --seed 1 --quiet 2> ROOM.log
    sed -i 's/\\x1b\\[[0-9;]*m//g' *.log
    python3 belief-drift.py '*.log'
Per straight FORWARD (heading within 0.1 rad, 0.3-0.6 m between two MOVE_DONE samples): the
change of the belief's error less the corrections applied in between, in the body's frame;
per correction, whether it moved the belief nearer the truth; and the across drift against the
heading error at the FORWARD's start times its length.
"""
import glob, math, re, sys

def num(key, line):
    return float(re.search(r'\b' + key + r'=([-0-9.eNa]+)', line).group(1))

drift, fixes, heading = [], [], []
for path in sorted(glob.glob(sys.argv[1])):
    if 'belief corrected' not in open(path).read():
        continue  # a log without the pilot's corrections cannot be split
    prev, fix = None, [0.0, 0.0]
    for line in open(path):
        if 'belief corrected' in line and prev:
            fa, fl, th = num('fix.along_m', line), num('fix.left_m', line), prev[2]
            fx, fy = fa * math.cos(th) - fl * math.sin(th), fa * math.sin(th) + fl * math.cos(th)
            before = math.hypot(prev[0] + fix[0], prev[1] + fix[1])
            fix = [fix[0] - fx, fix[1] - fy]
            fixes.append(before - math.hypot(prev[0] + fix[0], prev[1] + fix[1]))
        if 'move_done=true' not in line:
            continue
        ex, ey, th, bx, by, he = (num(k, line) for k in ('ex', 'ey', 'th', 'bx', 'by', 'heading_error'))
        if prev:
            moved = math.hypot(bx - prev[3], by - prev[4])
            turned = abs(math.atan2(math.sin(th - prev[2]), math.cos(th - prev[2])))
            if turned < 0.1 and 0.3 < moved < 0.6:
                dx, dy = ex - prev[0] - fix[0], ey - prev[1] - fix[1]
                c, s = math.cos(th), math.sin(th)
                drift.append((dx * c + dy * s, -dx * s + dy * c))
                heading.append((math.radians(prev[5]) * moved, -dx * s + dy * c))
        prev, fix = (ex, ey, th, bx, by, he), [0.0, 0.0]
if not drift:
    sys.exit('no straight FORWARD found')
rms = lambda xs: math.sqrt(sum(x * x for x in xs) / len(xs))
print(f'{len(drift)} straight FORWARDs: drift rms along {1000 * rms([a for a, _ in drift]):.1f} mm, '
      f'across {1000 * rms([l for _, l in drift]):.1f} mm')
print(f'{len(fixes)} corrections: {sum(g > 0.0005 for g in fixes)} nearer the truth, '
      f'{sum(g < -0.0005 for g in fixes)} farther (by more than 0.5 mm)')
n = len(heading)
mx, my = sum(a for a, _ in heading) / n, sum(b for _, b in heading) / n
cov = sum((a - mx) * (b - my) for a, b in heading) / n
vx, vy = sum((a - mx) ** 2 for a, _ in heading) / n, sum((b - my) ** 2 for _, b in heading) / n
print(f'across drift against heading error x distance: correlation {cov / math.sqrt(vx * vy):.2f}, '
      f'slope {cov / vx:.2f}')
