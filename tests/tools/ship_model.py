#!/usr/bin/python3
"""tools/ship_model.py on a real model file (tests/data/half_box_v1.h5, a model of cgd-fit, given the
paper's c_corr and no /provenance as cgd-fit writes it): the copy carries the
four provenance texts of the TOML file (white space folded to one line), c_corr = 1 with --no-parcel-correction and
the model's own c_corr without it, and every other attribute and dataset of the input unchanged (compared one by
one); the input is not touched. Refused with exit 2, one line naming the file and the key, no traceback, no output
and no .part left: a key missing, an unknown key, an empty text, a file that is not TOML or not UTF-8, an input that
is not a model file, --no-parcel-correction on a parcel-fitted model, an existing output without --force, the output
the input itself.
usage: /usr/bin/python3 tests/tools/ship_model.py SOURCE_DIR"""
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile

import h5py
import numpy as np

from tool_check import check, failures, source  # noqa: E402  (tests/tools/tool_check.py)
tool = os.path.join(source, "tools", "ship_model.py")
fixture = os.path.join(source, "tests", "data", "half_box_v1.h5")
TEXT = {"made_by": "cgd-fit a.h5 b.h5\n  --operator grid", "resolved_runs": "two runs", "valid_for": "the test",
        "validation": "none"}


def toml(path, texts):
    with open(path, "w") as f:
        for k, v in texts.items():
            f.write(f'{k} = """{v}"""\n' if "\n" in v else f'{k} = "{v}"\n')


def run(*args):
    return subprocess.run([sys.executable, tool, *args], capture_output=True, text=True)


def value(v):
    """A comparable form of an attribute or dataset: the bytes of numbers (NaN equal to NaN), the list of texts."""
    v = np.asarray(v)
    return (v.dtype.str, v.shape, v.tobytes()) if v.dtype.kind in "fiu" else (v.shape, v.tolist())


def contents(path):
    """{name: attributes and data} of every group and dataset but /provenance and /c_corr's a, k, source, fitted."""
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if name.startswith("provenance"):
                return
            attrs = {k: value(v) for k, v in obj.attrs.items()
                     if not (name == "c_corr" and k in ("a", "k", "source", "fitted"))}
            out[name] = (attrs, value(obj[()]) if isinstance(obj, h5py.Dataset) else None)
        out["/"] = ({k: value(v) for k, v in f.attrs.items()}, None)
        f.visititems(visit)
    return out


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


with tempfile.TemporaryDirectory() as tmp:
    model = os.path.join(tmp, "model.h5")
    shutil.copyfile(fixture, model)
    with h5py.File(model, "r+") as f:  # as cgd-fit writes it: the paper's c_corr, no /provenance
        del f["provenance"]
        c = f["c_corr"].attrs
        c["a"], c["k"], c["source"] = 0.0, 0.05, "paper"
    before = digest(model)
    prov = os.path.join(tmp, "prov.toml")
    toml(prov, TEXT)
    out = os.path.join(tmp, "shipped.h5")
    r = run(model, "--provenance", prov, "-o", out, "--no-parcel-correction")
    check(r.returncode == 0 and os.path.exists(out) and not os.path.exists(out + ".part"),
          f"written ({r.returncode}: {r.stdout.strip()} {r.stderr.strip()})")
    with h5py.File(out, "r") as f:
        p = {k: str(v) for k, v in f["provenance"].attrs.items()}
        c = dict(f["c_corr"].attrs)
    check(p == {**TEXT, "made_by": "cgd-fit a.h5 b.h5 --operator grid"},
          f"the four texts, each on one line ({p})")
    check(c["a"] == 1.0 and c["k"] == 0.0 and str(c["source"]) == "none" and c["fitted"] == 0, f"c_corr = 1 ({c})")
    check(contents(out) == contents(model), "every other attribute and dataset as the input's")
    check(digest(model) == before, "the input untouched")
    with h5py.File(model, "r") as f:
        own = dict(f["c_corr"].attrs)
    r = run(model, "--provenance", prov, "-o", out, "--force")
    with h5py.File(out, "r") as f:
        kept = dict(f["c_corr"].attrs)
    check(r.returncode == 0 and kept == own and own["k"] == 0.05, f"without --no-parcel-correction the model's own c_corr ({kept})")

    def refused(args, what, output=None):
        output = output or os.path.join(tmp, "refused.h5")
        r = run(*args, "-o", output)
        ok = r.returncode == 2 and what in r.stderr and r.stderr.startswith("ship_model.py: ") and \
            "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1 and \
            not os.path.exists(output + ".part")
        if output.endswith("refused.h5"):
            ok = ok and not os.path.exists(output)
        check(ok, f"{what}: exit 2 ({r.returncode}: {r.stderr.strip()})")

    for name, texts, what in (("missing", {k: v for k, v in TEXT.items() if k != "validation"}, "'validation' missing"),
                              ("extra", {**TEXT, "author": "x"}, "'author' is not a provenance text"),
                              ("empty", {**TEXT, "valid_for": " "}, "'valid_for' is ' '")):
        bad = os.path.join(tmp, name + ".toml")
        toml(bad, texts)
        refused([model, "--provenance", bad], f"{bad}: key {what}")
    notoml = os.path.join(tmp, "bad.toml")
    with open(notoml, "w") as f:
        f.write("made_by = \n")
    refused([model, "--provenance", notoml], f"{notoml}: not TOML")
    latin1 = os.path.join(tmp, "latin1.toml")
    with open(latin1, "wb") as f:
        f.write('made_by = "Sundaresan \u00e9"\n'.encode("latin-1"))
    refused([model, "--provenance", latin1], f"{latin1}: not TOML")
    fitted = os.path.join(tmp, "fitted.h5")  # a model after cgd-fit --parcel-fit
    shutil.copyfile(model, fitted)
    with h5py.File(fitted, "r+") as f:
        f["c_corr"].attrs["a_fit"], f["c_corr"].attrs["fitted"] = 0.4, 1
    refused([fitted, "--provenance", prov, "--no-parcel-correction"], "/c_corr was fitted")
    filtered = os.path.join(source, "data", "filtered", "half_phi0.02.h5")
    refused([filtered, "--provenance", prov], "cgd_format is 'filtered'")
    refused([model, "--provenance", prov], "exists (--force to overwrite)", output=out)
    refused([model, "--provenance", prov, "--force"], "is the input", output=model)
    check(digest(model) == before, "the input untouched by the refusals")

print(f"{failures()} failure(s)")
sys.exit(1 if failures() else 0)
