"""Hash of an EXR's pixel data (its chunks after the header and offset table), single part."""
import hashlib, struct, sys
def pixels(path):
    b = open(path, 'rb').read()
    i = 8
    while True:
        if b[i] == 0:
            i += 1
            break
        n = b.index(b'\0', i); t = b.index(b'\0', n + 1)
        size = struct.unpack('<i', b[t + 1:t + 5])[0]
        i = t + 5 + size
    first = struct.unpack('<Q', b[i:i + 8])[0]
    return hashlib.sha256(b[first:]).hexdigest()[:16]
for p in sys.argv[1:]:
    print(p.split('/')[-1], pixels(p))
