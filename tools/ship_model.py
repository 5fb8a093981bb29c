#!/usr/bin/python3
"""Make a model file of cgd-fit into the one shipped in data/models/: a copy with its /provenance and, optionally,
its parcel correction switched off (docs/schema-drag-model.md "/provenance").

A shipped model says in the file how it was made and what it is valid for: the text attributes made_by,
resolved_runs, valid_for and validation of /provenance (cgd-export copies them into its header; the ShippedModels
tests ask for them). They come from a TOML file kept in the repository beside the model it describes, so the text is
reviewed as text and the file can be made again from it:

    made_by = "cgd-fit data/filtered/half_phi0.02.h5 ... --operator grid --width-exponent fit"
    resolved_runs = "..."
    valid_for = "..."
    validation = "..."

(each a non-empty string; another key is refused). --no-parcel-correction sets /c_corr to a = 1, k = 0,
source "none", fitted 0 (c_corr(alpha) = 1: the model validated without a parcel correction, as
data/models/half_box.h5 is); a model whose c_corr was fitted (cgd-fit --parcel-fit: /c_corr a_fit) is refused with it
(ship that model with its fitted correction, or the model it was fitted from). Nothing else changes: the curves,
bands, sources and root attributes are those cgd-fit wrote.

usage: /usr/bin/python3 tools/ship_model.py MODEL.h5 --provenance TEXT.toml -o OUT.h5 [--no-parcel-correction]
           [--force]
The output is written whole or not at all (a copy under OUT.part, renamed when complete); it is never the input.
Exit status 0; 2 for a model that is not a drag-model file, a TOML file that does not parse (or is not UTF-8), lacks
a key or has another, --no-parcel-correction on a parcel-fitted model, an existing output without --force, or the
output the same file as the input.
(Debian's h5py belongs to /usr/bin/python3.)"""
import argparse
import os
import shutil
import sys

try:
    import tomllib
    import h5py
except ImportError as e:
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from system_python import reexec_or_exit
    reexec_or_exit(__file__, e, ["python3-h5py"])

KEYS = ("made_by", "resolved_runs", "valid_for", "validation")


def fail(message):
    sys.stderr.write(f"ship_model.py: {message}\n")
    sys.exit(2)


def read_provenance(path):
    """The four texts of a provenance TOML file, checked (exit 2 naming the file and the key)."""
    try:
        with open(path, "rb") as f:
            text = tomllib.load(f)
    except OSError as e:
        fail(f"{path}: cannot read ({e.strerror})")
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        fail(f"{path}: not TOML ({e})")
    for key in text:
        if key not in KEYS:
            fail(f"{path}: key '{key}' is not a provenance text; allowed: {', '.join(KEYS)}")
    for key in KEYS:
        if key not in text:
            fail(f"{path}: key '{key}' missing; a shipped model needs {', '.join(KEYS)}")
        if not isinstance(text[key], str) or not text[key].strip():
            fail(f"{path}: key '{key}' is {text[key]!r}; expected a non-empty string")
    return {k: " ".join(text[k].split()) for k in KEYS}  # one line each, as cgd-export prints them


def check_model(path, no_parcel_correction):
    try:
        with h5py.File(path, "r") as f:
            kind = f.attrs.get("cgd_format", b"")
            kind = kind.decode() if isinstance(kind, bytes) else str(kind)
            if kind != "drag_model":
                fail(f"{path}: attribute cgd_format is '{kind}'; expected 'drag_model' (a model file of cgd-fit)")
            if "c_corr" not in f:
                fail(f"{path}: /c_corr missing (not a model file of cgd-fit)")
            if no_parcel_correction and "a_fit" in f["c_corr"].attrs:
                fail(f"{path}: /c_corr was fitted (cgd-fit --parcel-fit: attribute a_fit); --no-parcel-correction "
                     "would leave its fit contradicting c_corr = 1: ship it with its correction, or the model it was "
                     "fitted from")
    except OSError as e:
        fail(f"{path}: not an HDF5 file ({e})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("model")
    ap.add_argument("--provenance", required=True, help="TOML file of made_by, resolved_runs, valid_for, validation")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--no-parcel-correction", action="store_true", help="c_corr = 1 (a = 1, k = 0, source none)")
    ap.add_argument("--force", action="store_true", help="overwrite an existing output")
    a = ap.parse_args()
    check_model(a.model, a.no_parcel_correction)
    texts = read_provenance(a.provenance)
    if os.path.exists(a.output):
        if os.path.samefile(a.output, a.model):
            fail(f"{a.output}: is the input; write the shipped copy elsewhere")
        if not a.force:
            fail(f"{a.output}: exists (--force to overwrite)")
    part = a.output + ".part"
    done = False
    try:
        shutil.copyfile(a.model, part)
        with h5py.File(part, "r+") as f:
            g = f.require_group("provenance")
            for key in list(g.attrs):
                del g.attrs[key]
            for key, value in texts.items():
                g.attrs[key] = value
            if a.no_parcel_correction:
                c = f["c_corr"].attrs
                c["a"], c["k"], c["source"], c["fitted"] = 1.0, 0.0, "none", 0
        with open(part, "rb") as f:
            os.fsync(f.fileno())
        os.replace(part, a.output)
        done = True
    except OSError as e:
        fail(f"{a.output}: not written ({e})")
    finally:
        if not done and os.path.exists(part):
            os.remove(part)
    print(f"wrote {a.output}: /provenance from {a.provenance}"
          + (", c_corr = 1" if a.no_parcel_correction else ""))


if __name__ == "__main__":
    main()
