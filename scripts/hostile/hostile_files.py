"""Hostile files and paths: every kind of input and output the battery puts in a case's
directory. Each maker takes the case directory, the name to create and the fixtures'
directory, and returns nothing; the battery snapshots the directory afterwards."""
import json
import os
import random
import shutil
import stat
import struct
import zlib
from typing import Callable, Dict

# ---------------------------------------------------------------------------------------
# Image bytes


def png_bytes(w: int, h: int, bitdepth: int = 8, idat: bytes = None) -> bytes:
    def chunk(t: bytes, b: bytes) -> bytes:
        return struct.pack(">I", len(b)) + t + b + struct.pack(">I", zlib.crc32(t + b) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", w, h, bitdepth, 0, 0, 0, 0)
    if idat is None:
        row = b"\x00" + bytes((x * 37) & 0xFF for x in range(w * bitdepth // 8))
        idat = zlib.compress(row * h)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")


def tiff_shared_strips(w: int, h: int) -> bytes:
    """An uncompressed 8-bit grey TIFF of w x h px whose every strip (one row each) is the
    same w bytes: a small file declaring a large image."""
    data_off = 8
    data = bytes((x * 7) & 0xFF for x in range(w))
    offs_off = data_off + len(data)
    offs = struct.pack(f"<{h}I", *([data_off] * h))
    cnts_off = offs_off + len(offs)
    cnts = struct.pack(f"<{h}I", *([w] * h))
    ifd_off = cnts_off + len(cnts)
    entries = [
        (256, 4, 1, w), (257, 4, 1, h), (258, 3, 1, 8), (259, 3, 1, 1), (262, 3, 1, 1),
        (273, 4, h, offs_off), (278, 4, 1, 1), (279, 4, h, cnts_off),
    ]
    ifd = struct.pack("<H", len(entries))
    for tag, typ, n, v in entries:
        if typ == 3 and n == 1:
            ifd += struct.pack("<HHIHH", tag, typ, n, v, 0)
        else:
            ifd += struct.pack("<HHII", tag, typ, n, v)
    ifd += struct.pack("<I", 0)
    return b"II*\x00" + struct.pack("<I", ifd_off) + data + offs + cnts + ifd


# ---------------------------------------------------------------------------------------
# Input kinds: (maker, expectation). A maker replaces dest (a name in d) by the kind.


def _write(p: str, b: bytes) -> None:
    with open(p, "wb") as f:
        f.write(b)


def _valid_bytes(fx: str, src: str) -> bytes:
    with open(os.path.join(fx, src), "rb") as f:
        return f.read()


def _rm(p: str) -> None:
    if os.path.islink(p) or os.path.isfile(p):
        os.unlink(p)
    elif os.path.isdir(p):
        shutil.rmtree(p)


def dataset_with_image(kind: str, d: str, fx: str, seed: int) -> None:
    """Writes d/dataset.json: the fixtures' dataset with its first view's image replaced by
    an image input of `kind` (a device path as is, else made by make_input as view0.png)."""
    with open(os.path.join(fx, "dataset.json")) as f:
        ds = json.load(f)
    if kind.startswith("/dev/"):
        ds["views"][0]["image"] = kind
    else:
        make_input(kind, d, "view0.png", fx, os.path.join("simimg", "views", "view00.png"), "obs.json", seed)
        ds["views"][0]["image"] = "view0.png"
    with open(os.path.join(d, "dataset.json"), "w") as f:
        json.dump(ds, f)


def make_input(kind: str, d: str, dest: str, fx: str, src: str, other: str, seed: int) -> None:
    p = os.path.join(d, dest)
    if os.path.lexists(p):
        _rm(p)
    rnd = random.Random(f"{seed}:{kind}:{dest}")
    if kind == "missing":
        return
    if kind == "directory":
        os.makedirs(p)
        _write(os.path.join(p, "inside.txt"), b"a file inside\n")
    elif kind == "fifo":
        os.mkfifo(p)
    elif kind == "chardev":  # a private clone of /dev/null
        os.mknod(p, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    elif kind == "empty":
        _write(p, b"")
    elif kind == "truncated":
        b = _valid_bytes(fx, src)
        _write(p, b[: len(b) // 2])
    elif kind == "truncated-1":
        b = _valid_bytes(fx, src)
        _write(p, b[:-2] if b.endswith(b"\n") else b[:-1])
    elif kind == "random":
        _write(p, bytes(rnd.getrandbits(8) for _ in range(4096)))
    elif kind == "nul":
        _write(p, b"\x00" * 4096)
    elif kind == "wrong-format":
        _write(p, _valid_bytes(fx, other))
    elif kind == "json-null":
        _write(p, b"null")
    elif kind == "json-array":
        _write(p, b"[]")
    elif kind == "json-object":
        _write(p, b"{}")
    elif kind == "json-string":
        _write(p, b'"etlcal"')
    elif kind == "deep-nest":
        _write(p, b"[" * 200000 + b"]" * 200000)
    elif kind == "deep-nest-obj":
        _write(p, b'{"a":' * 100000 + b"1" + b"}" * 100000)
    elif kind == "huge-field":  # a valid file whose format tag is 10 MB long
        obj = json.loads(_valid_bytes(fx, src))
        obj["format"] = "x" * 10_000_000
        _write(p, json.dumps(obj).encode())
    elif kind == "unknown-format":
        obj = json.loads(_valid_bytes(fx, src))
        obj["format"] = obj.get("format", "etlcal.x/1").replace("/1", "/999")
        _write(p, json.dumps(obj).encode())
    elif kind == "no-format":
        obj = json.loads(_valid_bytes(fx, src))
        obj.pop("format", None)
        _write(p, json.dumps(obj).encode())
    elif kind == "bom":
        _write(p, b"\xef\xbb\xbf" + _valid_bytes(fx, src))
    elif kind == "utf16":
        _write(p, _valid_bytes(fx, src).decode("utf-8").encode("utf-16"))
    elif kind == "dup-keys":
        b = _valid_bytes(fx, src).decode()
        i = b.index("{") + 1
        _write(p, (b[:i] + '"format": "etlcal.other/1",' + b[i:]).encode())
    elif kind == "trailing-garbage":
        _write(p, _valid_bytes(fx, src) + b"\n}{garbage")
    elif kind == "sparse-1g":
        with open(p, "wb") as f:
            f.truncate((1 << 30) + 1)
    elif kind == "symlink-loop":
        os.symlink(dest + ".loop", p)
        os.symlink(dest, p + ".loop")
    elif kind == "dangling":
        os.symlink("does-not-exist/" + dest, p)
    elif kind == "symlink-valid":
        shutil.copy(os.path.join(fx, src), p + ".real")
        os.symlink(os.path.basename(p) + ".real", p)
    elif kind == "symlink-dev-zero":
        os.symlink("/dev/zero", p)
    elif kind == "unreadable":
        shutil.copy(os.path.join(fx, src), p)
        os.chmod(p, 0)
    # images
    elif kind == "text-as-image":
        _write(p, b"this is not an image\n" * 10)
    elif kind == "png-huge-header":
        _write(p, png_bytes(65535, 65535, idat=zlib.compress(b"\x00" * 64)))
    elif kind == "png-16k-header":
        _write(p, png_bytes(16384, 16384, idat=zlib.compress(b"\x00" * 64)))
    elif kind == "png-1x1":
        _write(p, png_bytes(1, 1))
    elif kind == "png-1x5000":
        _write(p, png_bytes(5000, 1))
    elif kind == "png-zero":
        _write(p, png_bytes(0, 0, idat=zlib.compress(b"")))
    elif kind == "png-bad-crc":
        b = bytearray(_valid_bytes(fx, src))
        b[29] ^= 0xFF  # inside IHDR's CRC
        _write(p, bytes(b))
    elif kind == "png-flipped-bytes":
        b = bytearray(_valid_bytes(fx, src))
        for _ in range(64):
            b[rnd.randrange(100, len(b))] ^= 0xFF
        _write(p, bytes(b))
    elif kind == "gif-header":
        _write(p, b"GIF89a" + bytes(rnd.getrandbits(8) for _ in range(512)))
    elif kind == "tiff-huge-header":
        _write(p, _tiff_header_only(70000, 70000))
    elif kind == "tiff-256mpx-shared":
        _write(p, tiff_shared_strips(16000, 16000))
    elif kind == "jpeg-as-png":
        _write(p, _valid_bytes(fx, "z1.jpg"))
    elif kind == "png-16bit":
        _write(p, _valid_bytes(fx, "img16.png"))
    # csv
    elif kind == "csv-header-only":
        _write(p, b"temperature_c,e_in_ma,e_t_ma\n")
    elif kind == "csv-wrong-header":
        _write(p, b"t,e,et\n" + b"\n".join(_valid_bytes(fx, src).splitlines()[1:]))
    elif kind == "csv-nan":
        lines = _valid_bytes(fx, src).splitlines()
        lines[3] = b"NaN,NaN,NaN"
        _write(p, b"\n".join(lines) + b"\n")
    elif kind == "csv-1e999":
        lines = _valid_bytes(fx, src).splitlines()
        lines[2] = b"1e999,-1e999,1e999"
        _write(p, b"\n".join(lines) + b"\n")
    elif kind == "csv-1e308":
        lines = _valid_bytes(fx, src).splitlines()
        lines = [lines[0]] + [b"1e308,1e308,1e308"] + lines[2:]
        _write(p, b"\n".join(lines) + b"\n")
    elif kind == "csv-huge-field":
        _write(p, b"temperature_c,e_in_ma,e_t_ma\n" + b"1" * 10_000_000 + b",2,3\n")
    elif kind == "csv-one-row":
        _write(p, b"\n".join(_valid_bytes(fx, src).splitlines()[:2]) + b"\n")
    elif kind == "csv-identical-rows":
        _write(p, b"temperature_c,e_in_ma,e_t_ma\n" + b"30,100,1\n" * 1000)
    elif kind == "csv-crlf":
        _write(p, _valid_bytes(fx, src).replace(b"\n", b"\r\n"))
    elif kind == "csv-ragged":
        _write(p, b"temperature_c,e_in_ma,e_t_ma\n30,100\n31,100,1,5\n,,\n")
    elif kind == "csv-many-rows":  # 200000 rows: a big table still fits
        rows = [f"{27 + (k % 11)},{40 + (k % 200)},{(k % 7) * 0.1}" for k in range(200000)]
        _write(p, ("temperature_c,e_in_ma,e_t_ma\n" + "\n".join(rows) + "\n").encode())
    else:
        raise ValueError(f"unknown input kind {kind}")


def _tiff_header_only(w: int, h: int) -> bytes:
    entries = [(256, 4, 1, w), (257, 4, 1, h), (258, 3, 1, 8), (259, 3, 1, 1), (262, 3, 1, 1),
               (273, 4, 1, 8), (278, 4, 1, h), (279, 4, 1, 16)]
    ifd = struct.pack("<H", len(entries))
    for tag, typ, n, v in entries:
        ifd += struct.pack("<HHIHH", tag, typ, n, v, 0) if typ == 3 else struct.pack("<HHII", tag, typ, n, v)
    ifd += struct.pack("<I", 0)
    return b"II*\x00" + struct.pack("<I", 24) + b"\x7f" * 16 + ifd


# Which kinds each file type gets, and what a command given one must do.
JSON_KINDS = ["missing", "directory", "fifo", "chardev", "empty", "truncated", "truncated-1", "random", "nul",
              "wrong-format", "json-null", "json-array", "json-object", "json-string", "deep-nest",
              "deep-nest-obj", "huge-field", "unknown-format", "no-format", "bom", "utf16", "dup-keys",
              "trailing-garbage", "sparse-1g", "symlink-loop", "dangling", "symlink-valid", "symlink-dev-zero",
              "unreadable", "/dev/zero", "/dev/null", "/dev/stdin"]
IMAGE_KINDS = ["missing", "directory", "fifo", "chardev", "empty", "truncated", "random", "nul", "text-as-image",
               "png-huge-header", "png-16k-header", "png-1x1", "png-1x5000", "png-zero", "png-bad-crc",
               "png-flipped-bytes", "gif-header", "tiff-huge-header", "tiff-256mpx-shared", "jpeg-as-png",
               "png-16bit", "sparse-1g", "symlink-loop", "dangling", "symlink-valid", "symlink-dev-zero",
               "/dev/zero", "/dev/null", "/dev/stdin"]
CSV_KINDS = ["missing", "directory", "fifo", "chardev", "empty", "truncated", "random", "nul", "wrong-format",
             "csv-header-only", "csv-wrong-header", "csv-nan", "csv-1e999", "csv-1e308", "csv-huge-field",
             "csv-one-row", "csv-identical-rows", "csv-crlf", "csv-ragged", "csv-many-rows", "bom", "utf16",
             "sparse-1g", "symlink-loop", "dangling", "symlink-valid", "/dev/zero", "/dev/null", "/dev/stdin"]

# kinds after which the command may well succeed (the file is still valid, or a readable
# variant of one); every other kind must be refused
MAY_SUCCEED = {"symlink-valid", "bom", "dup-keys", "jpeg-as-png", "png-16bit", "png-1x1", "png-1x5000",
               "csv-crlf", "csv-many-rows", "png-flipped-bytes", "unreadable", "tiff-256mpx-shared",
               "truncated-1", "csv-1e308", "csv-identical-rows", "csv-one-row", "csv-nan", "csv-ragged"}
FAST_INPUT_KINDS = {"missing", "directory", "fifo", "/dev/zero", "truncated", "wrong-format", "symlink-loop",
                    "png-huge-header", "csv-huge-field", "deep-nest"}


def input_setup(kind: str, dest: str, src: str, other: str, seed: int, fx: str):
    """(setup function, argument to put in the command line)."""
    if kind.startswith("/dev/"):
        return (lambda d: None), kind

    def setup(d: str) -> None:
        make_input(kind, d, dest, fx, src, other, seed)

    return setup, dest


# ---------------------------------------------------------------------------------------
# Output kinds. A maker prepares the output token `tok` (relative) in d and returns
# (argument for the command line, outputs that may change on success, expectation).

LONG = "n" * 300


def make_file_output(kind: str, d: str, tok: str, an_input: str, seed: int):
    p = os.path.join(d, tok)
    rnd = random.Random(f"{seed}:{kind}:{tok}")
    earlier = b"an earlier output " + bytes(rnd.getrandbits(8) for _ in range(64)) + b"\n"
    if kind == "new":
        return tok, [tok], "ok"
    if kind == "earlier":
        _write(p, earlier)
        return tok, [tok], "ok"
    if kind == "earlier-0600":
        _write(p, earlier)
        os.chmod(p, 0o600)
        return tok, [tok], "ok"
    if kind == "same-as-input":
        return an_input, [], "refuse"
    if kind == "same-as-input-dotted":
        return "./" + an_input, [], "refuse"
    if kind == "symlink-to-input":
        os.symlink(an_input, p)
        return tok, [], "refuse"
    if kind == "hardlink-to-input":
        os.link(os.path.join(d, an_input), p)
        return tok, [], "refuse"
    if kind == "symlink-to-earlier":
        _write(os.path.join(d, "earlier-target"), earlier)
        os.symlink("earlier-target", p)
        return tok, [tok, "earlier-target"], "ok"
    if kind == "dangling":
        os.symlink("nowhere/" + tok, p)
        return tok, [], "refuse"
    if kind == "symlink-loop":
        os.symlink(tok + ".loop", p)
        os.symlink(tok, p + ".loop")
        return tok, [], "refuse"
    if kind == "directory":
        os.makedirs(p)
        _write(os.path.join(p, "keep.txt"), earlier)
        return tok, [], "refuse"
    if kind == "fifo":
        os.mkfifo(p)
        return tok, [], "refuse"
    if kind == "chardev":
        os.mknod(p, stat.S_IFCHR | 0o666, os.makedev(1, 3))
        return tok, [], "refuse"
    if kind == "readonly":
        _write(p, earlier)
        os.chmod(p, 0o444)
        return tok, [], "refuse"
    if kind == "in-missing-dir":
        return os.path.join("a", "b", "c", tok), ["a"], "ok"
    if kind == "in-readonly-dir":
        os.makedirs(os.path.join(d, "ro"))
        os.chmod(os.path.join(d, "ro"), 0o555)
        return os.path.join("ro", tok), [os.path.join("ro", tok)], "any"  # root may write there
    if kind == "long-component":
        return LONG + os.path.splitext(tok)[1], [], "refuse"
    if kind == "long-path":
        parts = ["p" * 50] * 5 + [tok]
        return os.path.join(*parts), ["p" * 50], "ok"
    if kind == "file-as-parent":
        return os.path.join("sentinel.txt", tok), [], "refuse"
    if kind == "empty":
        return "", [], "refuse"
    if kind == "trailing-slash":
        return tok + "/", [tok], "any"
    if kind == "dot":
        return ".", [], "refuse"
    if kind == "stale-temp":
        _write(p, earlier)
        _write(os.path.join(d, f".{os.path.basename(tok)}.tmp999999"), b"stale temporary of a dead process\n")
        return tok, [tok, f".{os.path.basename(tok)}.tmp999999"], "ok"
    if kind == "absolute":  # the case's folder is put in when the case runs
        return "{CASE}/" + tok, [tok], "ok"
    raise ValueError(kind)


FILE_OUT_KINDS = ["new", "earlier", "earlier-0600", "same-as-input", "same-as-input-dotted", "symlink-to-input",
                  "hardlink-to-input", "symlink-to-earlier", "dangling", "symlink-loop", "directory", "fifo",
                  "chardev", "readonly", "in-missing-dir", "in-readonly-dir", "long-component", "long-path",
                  "file-as-parent", "empty", "trailing-slash", "dot", "stale-temp", "absolute"]
FAST_OUT_KINDS = {"same-as-input", "symlink-to-input", "directory", "fifo", "readonly", "chardev"}


def make_dir_output(kind: str, d: str, tok: str, an_input: str, earlier_set: str, seed: int):
    """earlier_set: a fixture folder holding an earlier set of this verb (or None)."""
    p = os.path.join(d, tok)
    if kind == "new":
        return tok, [tok], "ok"
    if kind == "earlier-set":
        shutil.copytree(earlier_set, p, symlinks=True)
        return tok, [tok], "ok"
    if kind == "earlier-set-slash":
        shutil.copytree(earlier_set, p, symlinks=True)
        return tok + "/", [tok], "ok"
    if kind == "empty-dir":
        os.makedirs(p)
        return tok, [tok], "ok"
    if kind == "foreign":
        shutil.copytree(earlier_set, p, symlinks=True)
        _write(os.path.join(p, "my-notes.txt"), b"the user's own file\n")
        return tok, [], "refuse"
    if kind == "only-foreign":
        os.makedirs(p)
        _write(os.path.join(p, "my-file.json"), b'{"the user": "file"}\n')
        return tok, [], "refuse"
    if kind == "member-name-no-marker":
        # a folder without .etlcal-set holding a user's file that has the name of one of
        # the set's files: is it taken for an earlier set?
        os.makedirs(p)
        _write(os.path.join(p, MEMBER.get(tok, "index.html")), b'{"the user": "file, not etlcal\'s"}\n')
        return tok, [tok], "refuse"
    if kind == "file":
        _write(p, b"a file where a folder is expected\n")
        return tok, [], "refuse"
    if kind == "same-as-input-dir":
        return ".", [], "refuse"
    if kind == "symlink-to-earlier-set":
        shutil.copytree(earlier_set, os.path.join(d, "real-set"), symlinks=True)
        os.symlink("real-set", p)
        return tok, [tok, "real-set"], "any"
    if kind == "dangling":
        os.symlink("nowhere/" + tok, p)
        return tok, [], "any"
    if kind == "symlink-loop":
        os.symlink(tok + ".loop", p)
        os.symlink(tok, p + ".loop")
        return tok, [], "refuse"
    if kind == "fifo":
        os.mkfifo(p)
        return tok, [], "refuse"
    if kind == "chardev":
        os.mknod(p, stat.S_IFCHR | 0o666, os.makedev(1, 3))
        return tok, [], "refuse"
    if kind == "readonly-earlier":
        shutil.copytree(earlier_set, p, symlinks=True)
        os.chmod(p, 0o555)
        return tok, [tok], "any"
    if kind == "in-missing-dir":
        return os.path.join("a", "b", tok), ["a"], "ok"
    if kind == "long-component":
        return LONG, [], "refuse"
    if kind == "file-as-parent":
        return os.path.join("sentinel.txt", tok), [], "refuse"
    if kind == "empty":
        return "", [], "refuse"
    if kind == "stale-temp":
        _write(os.path.join(d, f".{tok}.tmp999999"), b"stale\n")
        os.makedirs(os.path.join(d, f".{tok}.tmp999998"))
        return tok, [tok, f".{tok}.tmp999999", f".{tok}.tmp999998"], "ok"
    if kind == "input-as-dir":  # the folder named is an input file
        return an_input, [], "refuse"
    raise ValueError(kind)


MEMBER = {"out": "observations.json", "rep": "index.html", "demo": "calibration.json", "st": "fig5.json",
          "und": "img.png"}
DIR_OUT_KINDS = ["new", "earlier-set", "earlier-set-slash", "empty-dir", "foreign", "only-foreign",
                 "member-name-no-marker", "file",
                 "same-as-input-dir", "symlink-to-earlier-set", "dangling", "symlink-loop", "fifo", "chardev",
                 "readonly-earlier", "in-missing-dir", "long-component", "file-as-parent", "empty", "stale-temp",
                 "input-as-dir"]
FAST_DIR_KINDS = {"foreign", "file", "same-as-input-dir", "fifo", "earlier-set"}


def output_makers() -> Dict[str, Callable]:
    return {"file": make_file_output, "dir": make_dir_output}
