# Before | after comparisons of the image-quality renders (issue 13), no PIL needed:
# crops of before/NAME.png and after/NAME.png, enlarged by nearest neighbour, side by side
# with a white gap. usage: python3 compare.py   (writes compare-*.png here)
import importlib.util, os
here = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location("crop_io", os.path.join(here, "crop_io.py"))
io = importlib.util.module_from_spec(spec); spec.loader.exec_module(io)

def crop(px, w, x, y, cw, ch, k):
    rows = []
    for yy in range(y, y + ch):
        row = b''.join(px[(yy * w + xx) * 3:(yy * w + xx) * 3 + 3] * k for xx in range(x, x + cw))
        rows.extend([row] * k)
    return rows

REGIONS = [  # name, scene, x, y, w, h, scale
    ("sphere-full", "sphere-on-floor", 0, 0, 256, 256, 2),
    ("sphere-interior", "sphere-on-floor", 64, 40, 128, 128, 3),
    ("glass-full", "glass", 0, 0, 256, 256, 2),
    ("glass-floor", "glass", 20, 170, 110, 70, 3),
    ("glass-wine", "glass", 80, 80, 100, 80, 3),
    ("lung-full", "lung-ct", 0, 0, 256, 256, 2),
]
for name, scene, x, y, cw, ch, k in REGIONS:
    wb, hb, pb = io.load(os.path.join(here, "before", scene + ".png"))
    wa, ha, pa = io.load(os.path.join(here, "after", scene + ".png"))
    a, b = crop(pb, wb, x, y, cw, ch, k), crop(pa, wa, x, y, cw, ch, k)
    gap = b'\xff' * (3 * 6)
    rows = [ra + gap + rb for ra, rb in zip(a, b)]
    io.save(os.path.join(here, "compare-" + name + ".png"), 2 * cw * k + 6, ch * k, b''.join(rows))
    print("compare-" + name + ".png")

# Median-residual noise, mean |pixel - median of its 3x3| (of 255, all channels), in the
# regions docs/NOTES.md quotes ("Clean images").
def noise(path, x0, y0, x1, y1):
    w, h, px = io.load(path)
    tot = n = 0
    for y in range(max(1, y0), min(h - 1, y1)):
        for x in range(max(1, x0), min(w - 1, x1)):
            for c in range(3):
                nb = sorted(px[((y + dy) * w + (x + dx)) * 3 + c] for dy in (-1, 0, 1) for dx in (-1, 0, 1))
                tot += abs(px[(y * w + x) * 3 + c] - nb[4]); n += 1
    return tot / n

for scene, box in [("lung-ct", (40, 100, 220, 220)), ("glass", (95, 85, 165, 150)),
                   ("sphere-on-floor", (90, 60, 170, 130))]:
    b = noise(os.path.join(here, "before", scene + ".png"), *box)
    a = noise(os.path.join(here, "after", scene + ".png"), *box)
    print("%s: median residual %.2f -> %.2f of 255 in %s" % (scene, b, a, box))
