import sys, math
# First N FLASER scans of a CARMEN log (robot standing still) as an ASCII PLY in the laser frame.
log, n, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
pts = []
with open(log) as f:
    k = 0
    for line in f:
        if not line.startswith('FLASER'): continue
        v = line.split(); m = int(v[1])
        step = math.pi / (m - 1) if m == 361 else math.pi / 180
        for i in range(m):
            r = float(v[2 + i])
            if r <= 0.0 or r >= 80.0: continue
            a = -math.pi / 2 + i * step
            pts.append((r * math.cos(a), r * math.sin(a), 0.0, k, i))
        k += 1
        if k == n: break
with open(out, 'w') as f:
    f.write('ply\nformat ascii 1.0\ncomment %d FLASER scans of %s in the laser frame (x forward, y left; m)\n' % (n, log.split('/')[-1]))
    f.write('element vertex %d\nproperty float x\nproperty float y\nproperty float z\nproperty int scan\nproperty int beam\nend_header\n' % len(pts))
    for p in pts: f.write('%.4f %.4f %.1f %d %d\n' % p)
print(len(pts))
