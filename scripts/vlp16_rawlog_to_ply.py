import gzip, math, struct, sys
# Velodyne VLP-16 data packets found in a file (e.g. an MRPT rawlog, gzip or not), decoded as an
# ASCII PLY in the sensor frame. Packet layout and angles from the VLP-16 user manual: 12 blocks
# of 100 bytes (0xFFEE, azimuth in 0.01 deg, 2 x 16 returns of uint16 range in 2 mm and uint8
# reflectivity); x = r cos(w) sin(a), y = r cos(w) cos(a), z = r sin(w) (a clockwise from +y).
# Usage: python3 vlp16_rawlog_to_ply.py IN OUT.ply
src, out = sys.argv[1], sys.argv[2]
raw = open(src, 'rb').read()
if raw[:2] == b'\x1f\x8b':
    raw = gzip.decompress(raw)
ELEV = [-15, 1, -13, 3, -11, 5, -9, 7, -7, 9, -5, 11, -3, 13, -1, 15]  # deg, by channel
FLAG = b'\xff\xee'


def is_packet(p):
    return p + 1200 <= len(raw) and all(raw[p + 100 * b:p + 100 * b + 2] == FLAG for b in range(12))


pts, p = [], 0
while True:
    p = raw.find(FLAG, p)
    if p < 0:
        break
    if not is_packet(p):
        p += 1
        continue
    az = [struct.unpack_from('<H', raw, p + 100 * b + 2)[0] / 100.0 for b in range(12)]
    for b in range(12):
        # the second firing of a block sits halfway to the next block's azimuth
        step = ((az[b + 1] if b < 11 else az[b] + (az[b] - az[b - 1])) - az[b]) % 360.0
        for fire in range(2):
            for ch in range(16):
                o = p + 100 * b + 4 + 3 * (16 * fire + ch)
                r = struct.unpack_from('<H', raw, o)[0] * 0.002
                if r <= 0.0:
                    continue  # no return
                t = (fire * 55.296 + ch * 2.304) / 110.592  # firing time within the block
                a = math.radians((az[b] + step * t) % 360.0)
                w = math.radians(ELEV[ch])
                pts.append((r * math.cos(w) * math.sin(a), r * math.cos(w) * math.cos(a),
                            r * math.sin(w), raw[o + 2], ch))
    p += 1200
with open(out, 'w') as f:
    f.write('ply\nformat ascii 1.0\ncomment VLP-16 returns decoded from %s (sensor frame, m)\n' % src.split('/')[-1])
    f.write('element vertex %d\nproperty float x\nproperty float y\nproperty float z\n' % len(pts))
    f.write('property uchar intensity\nproperty uchar ring\nend_header\n')
    for q in pts:
        f.write('%.3f %.3f %.3f %d %d\n' % q)
print(len(pts))
