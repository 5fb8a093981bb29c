#!/usr/bin/python3
"""The checksum seal of cgd's checkpoints (checkpoint.h5, format version 2; docs/schema-run.md "Seal and
validation").

cgd writes a checkpoint with a 512-byte user block at its start (HDF5 and h5py skip it) holding one line,
"cgd-seal fnv1a64 <16 hex digits> bytes <n>\\n", zero-padded: the FNV-1a 64-bit hash and the length of every
byte after the user block (core/h5.hpp). A restart refuses a checkpoint whose bytes do not match, and a
version-2 checkpoint without a seal. No other cgd file is sealed: they are read and validated by content,
so editing them with h5py needs nothing of this tool. Someone who edits a checkpoint on purpose (and knows
the restart will then continue from the edited state) seals it again with `cgd_seal.py seal FILE`.

    cgd_seal.py check FILE...   exit 0 if every file's seal matches (or it has none), 2 otherwise
    cgd_seal.py seal FILE...    rewrite the seal of files that have cgd's user block
"""
import sys

SEAL_BYTES = 512
MAGIC = b"cgd-seal fnv1a64 "
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def fnv1a64(path, offset=SEAL_BYTES):
    h, n = 0xCBF29CE484222325, 0
    with open(path, "rb") as f:
        f.seek(offset)
        while True:
            chunk = f.read(1 << 20)
            if not chunk:
                break
            n += len(chunk)
            for b in chunk:
                h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}", n


def has_user_block(path):
    with open(path, "rb") as f:
        f.seek(SEAL_BYTES)
        return f.read(8) == HDF5_SIGNATURE


def seal(path):
    """Rewrite the seal of `path` (closed); False if the file has no cgd user block (left as it is)."""
    if not has_user_block(path):
        return False
    digest, n = fnv1a64(path)
    line = MAGIC + f"{digest} bytes {n}\n".encode()
    with open(path, "r+b") as f:
        f.write(line + b"\0" * (SEAL_BYTES - len(line)))
    return True


def check(path):
    """None if the seal matches or there is none; else a one-line description of the damage."""
    with open(path, "rb") as f:
        block = f.read(SEAL_BYTES)
    if not block.startswith(MAGIC):
        return None
    try:
        digest, _, n = block[len(MAGIC):].split(b"\n")[0].decode().split(" ")
        n = int(n)
    except ValueError:
        return "its checksum seal is unreadable"
    found, m = fnv1a64(path)
    if m != n:
        return f"found {m} bytes after the seal, expected {n}"
    if found != digest:
        return f"its contents do not match the checksum written with it (FNV-1a {found}, expected {digest})"
    return None


def main(argv):
    if len(argv) < 3 or argv[1] not in ("check", "seal"):
        print(__doc__.strip().splitlines()[-2:], file=sys.stderr)
        return 2
    status = 0
    for path in argv[2:]:
        if argv[1] == "seal":
            seal(path)
        elif (problem := check(path)) is not None:
            print(f"{path}: damaged: {problem}", file=sys.stderr)
            status = 2
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv))
