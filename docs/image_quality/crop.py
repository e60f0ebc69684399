# Crop + nearest-neighbour upscale of a PNG, no PIL needed.
# usage: python3 crop.py IN.png X Y W H SCALE OUT.png
import sys
from crop_io import load, save
src, x, y, cw, ch, k, out = sys.argv[1], *map(int, sys.argv[2:7]), sys.argv[7]
w, h, px = load(src)
rows = []
for yy in range(y, y+ch):
    row = b''.join(px[(yy*w+xx)*3:(yy*w+xx)*3+3] * k for xx in range(x, x+cw))
    rows.append(row * 1)
outpx = b''.join(r for r in rows for _ in range(k))
save(out, cw*k, ch*k, outpx)
