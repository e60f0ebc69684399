# PNG in (via `convert FILE.png ppm:-`) and out (zlib) without PIL, for crop.py and compare.py.
import subprocess, sys, zlib, struct
def load(path):
    d = subprocess.run(["convert", path, "ppm:-"], capture_output=True, check=True).stdout
    # parse P6 header
    parts = []; i = 0
    while len(parts) < 4:
        while d[i:i+1].isspace(): i += 1
        if d[i:i+1] == b'#':
            while d[i:i+1] != b'\n': i += 1
            continue
        j = i
        while not d[j:j+1].isspace(): j += 1
        parts.append(d[i:j]); i = j
    i += 1
    assert parts[0] == b'P6' and parts[3] == b'255', parts
    w, h = int(parts[1]), int(parts[2])
    return w, h, d[i:i+w*h*3]
def save(path, w, h, px):
    raw = b''.join(b'\x00' + px[y*w*3:(y+1)*w*3] for y in range(h))
    def chunk(t, b): return struct.pack('>I', len(b)) + t + b + struct.pack('>I', zlib.crc32(t + b) & 0xffffffff)
    open(path, 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0)) + chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b''))
