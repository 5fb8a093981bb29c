#!/usr/bin/python3
"""Damaged inputs are refused (issue 30; docs/schema-run.md "Seal and validation").

Files of every kind the tools read -- snapshot, checkpoint, series, filtered, drag_model, coarse_summary -- are
damaged the ways files get damaged: cut short, bytes overwritten, a dataset (or a summary's attribute) removed, a
value set to NaN, an array of the wrong shape, an attribute of the wrong type. Each damaged copy goes to the tools
that read it (cgd-filter, cgd-generate --restart, cgd-fit, cgd-fit --parcel-fit, cgd-export, cgd-show; one
tool per C++ reader: cgd-coarse --summarise reads series with the restart's reader, cgd-coarse and cgd-fit
--parcel-fit models with cgd-export's), each run with a time limit. Checked for every damage and tool: no signal, no hang, no
traceback; the cgd tools exit with status 2, a message naming the file, no output written, and a restart leaves
its run directory byte for byte as it was. cgd-show, an inspector, may show what it can read (exit 0) or refuse
with one line (exit 2).

One damage is not refused by every reader, by design: random bytes inside an array of a file without a seal
(every kind but the checkpoint) change numbers no content check can tell from data when they stay finite. That
case is run too ("random bytes"), checked for no signal and no hang, and its outcome printed; the checkpoint,
sealed, refuses it. A NaN in a (resealed) checkpoint and in a snapshot is also given to the restart and
the filter at 2 ranks (mpirun). Fixed seed; about 35 s. Environment: CGD_SOURCE_DIR, CGD_BINARY_DIR (set by CTest).
"""
import hashlib
import os
import random
import shutil
import subprocess
import sys
import tempfile

import h5py
import numpy as np

SRC = os.environ.get("CGD_SOURCE_DIR", os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
BIN = os.environ.get("CGD_BINARY_DIR", os.path.join(SRC, "build"))
PY = "/usr/bin/python3"
TIME_LIMIT_S = 60
sys.path.insert(0, os.path.join(SRC, "tools"))
import cgd_seal  # noqa: E402

failures = []


# Open MPI's start-up without UCX (half of each tool's 0.4 s here): one process talks to itself, two through
# shared memory. The tools read and refuse the same way with any transport.
SINGLE_PROCESS = {"OMPI_MCA_pml": "ob1", "OMPI_MCA_btl": "self"}
SHARED_MEMORY = {"OMPI_MCA_pml": "ob1", "OMPI_MCA_btl": "self,vader"}


def run(argv, stderr_only=False):
    transport = SHARED_MEMORY if os.path.basename(argv[0]) == "mpirun" else SINGLE_PROCESS
    try:
        p = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, errors="replace",
                           timeout=TIME_LIMIT_S, env={**os.environ, **transport})
        return p.returncode, p.stderr if stderr_only else p.stdout + p.stderr
    except subprocess.TimeoutExpired:
        return "hang", f"no answer in {TIME_LIMIT_S} s"


def tree_digest(path):
    """Every file under `path` with its bytes' hash: a run directory byte for byte."""
    out = {}
    for root, _, files in os.walk(path):
        for name in files:
            full = os.path.join(root, name)
            with open(full, "rb") as f:
                out[os.path.relpath(full, path)] = hashlib.sha256(f.read()).hexdigest()
    return out


# ---- the damages: each edits `path` in place; False when it does not apply to the file ------------------------
def cut_short(path, target, rng):
    os.truncate(path, int(os.path.getsize(path) * 0.6))
    return True


def overwrite_array(path, target, rng):
    """64 bytes of 0xff inside the raw data of `target` (floats become NaN, integers -1)."""
    with h5py.File(path, "r") as f:
        ds = f[target.dataset]
        offset, size = ds.id.get_offset(), ds.id.get_storage_size()
    if offset is None or size < 8:
        return False
    start = offset + 8 * rng.randrange(max(1, (size - 64) // 8 + 1))
    with open(path, "r+b") as f:
        f.seek(start)
        f.write(b"\xff" * min(64, size))
    return True


def overwrite_metadata(path, target, rng):
    """64 random bytes among the first 2 KiB after the superblock (object headers, B-trees, heaps)."""
    base = cgd_seal.SEAL_BYTES if cgd_seal.has_user_block(path) else 0
    start = base + 96 + rng.randrange(1900)
    with open(path, "r+b") as f:
        f.seek(start)
        f.write(bytes(rng.randrange(256) for _ in range(64)))
    return True


def random_bytes(path, target, rng):
    """64 random bytes in the middle of the file's largest array: finite garbage a content check may not see."""
    found = []
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: found.append((obj.id.get_storage_size(), obj.id.get_offset()))
                     if isinstance(obj, h5py.Dataset) and obj.id.get_offset() is not None else None)
    if not found or max(found)[0] < 128:
        return False
    size, offset = max(found)
    with open(path, "r+b") as f:
        f.seek(offset + size // 2 - 32)
        f.write(bytes(rng.randrange(256) for _ in range(64)))
    return True


def remove(path, target, rng):
    with h5py.File(path, "r+") as f:
        if target.removed.startswith("@"):
            del f.attrs[target.removed[1:]]
        else:
            del f[target.removed]
    return True


def nan_value(path, target, rng):
    with h5py.File(path, "r+") as f:
        if target.nan.startswith("@"):
            f.attrs[target.nan[1:]] = np.nan
        else:
            ds = f[target.nan]
            x = ds[()]
            x.flat[len(x.flat) // 2] = np.nan
            ds[...] = x
    return True


def wrong_shape(path, target, rng):
    with h5py.File(path, "r+") as f:
        if target.shape.startswith("@"):
            name = target.shape[1:]
            f.attrs[name] = np.array([float(np.ravel(f.attrs[name])[0])] * 2)
        else:
            x = f[target.shape][()]
            del f[target.shape]
            f[target.shape] = x[:-1] if x.ndim == 1 else x[:, :-1]
    return True


def wrong_type(path, target, rng):
    obj, name = target.attr
    with h5py.File(path, "r+") as f:
        f[obj].attrs[name] = "a string"
    return True


# Damages every reader must refuse, and those (random bytes) only a sealed file (the checkpoint) always refuses:
# elsewhere they must not crash or hang a tool, and their outcome is printed.
DAMAGES = [("cut short", cut_short), ("bytes overwritten (array)", overwrite_array), ("dataset removed", remove),
           ("NaN value", nan_value), ("wrong shape", wrong_shape), ("wrong attribute type", wrong_type)]
UNSEEN_UNLESS_SEALED = [("random bytes (metadata)", overwrite_metadata), ("random bytes (array)", random_bytes)]


class Target:
    """Where each damage lands in one kind of file."""

    def __init__(self, dataset, removed, nan, shape, attr):
        self.dataset, self.removed, self.nan, self.shape, self.attr = dataset, removed, nan, shape, attr


def main():
    tmp = tempfile.mkdtemp(prefix="cgd_damage_")
    try:
        return check_all(tmp)
    finally:
        if not os.environ.get("KEEP"):
            shutil.rmtree(tmp, ignore_errors=True)


def check_all(tmp):
    rng = random.Random(30)
    scene = os.path.join(SRC, "tests", "scenes", "small_suspension.toml")
    short = ["--set", "run.end_time=0.03", "--set", "run.dump_interval=0.01", "--quiet"]
    run_dir = os.path.join(tmp, "run")
    for argv in ([f"{BIN}/cgd-generate", scene, *short, "-o", run_dir],
                 [PY, os.path.join(SRC, "tests", "fit", "make_synthetic_filtered.py"), "--snapshots", "20", "--block",
                  "5", "-o", os.path.join(tmp, "filtered.h5")]):
        status, text = run(argv)
        if status != 0:
            print(text)
            print("FAIL: could not make the inputs")
            return 1
    status, text = run([f"{BIN}/cgd-fit", os.path.join(tmp, "filtered.h5"), "--bootstrap", "20", "--no-cross-validation",
                        "-o", os.path.join(tmp, "model.h5")])
    if status != 0:
        print(text)
        print("FAIL: could not fit the model")
        return 1
    sys.path.insert(0, os.path.join(SRC, "tests", "fit"))
    import synthetic_summary
    summaries = []
    for alpha, slip in ((1, 0.950), (2, 0.952), (2, 0.948), (3, 0.949), (4, 0.951)):
        d = os.path.join(tmp, "coarse", f"a{alpha}_{len(summaries)}")
        synthetic_summary.write(d, 0.05, alpha, len(summaries), slip)  # as tests/e2e/parcel_fit.sh writes them
        summaries.append(d)
    last_snapshot = sorted(os.listdir(os.path.join(run_dir, "snapshots")))[-1]
    restart = [f"{BIN}/cgd-generate", scene, *short[:2], "--set", "run.end_time=0.04", *short[4:], "--restart"]

    # kind: (the file in a fresh copy of its inputs, where the damages land, the tools that read it)
    # a tool: (name, argv for the copy's folder `w` and file `x`, outputs that must not appear, folder left unchanged)
    kinds = {
        "snapshot": (os.path.join("run", "snapshots", last_snapshot),
                     Target("particles/position", "particles/velocity", "fluid/eps_velocity", "particles/position",
                            ("params", "diameter_m")),
                     [("cgd-filter", lambda w, x: [f"{BIN}/cgd-filter", f"{w}/run", "--bootstrap", "20", "--quiet", "-o",
                                                   f"{w}/out.h5"], ["out.h5", "out.h5.tmp"], None)]),
        "checkpoint": (os.path.join("run", "checkpoint.h5"),
                       Target("particles/position", "particles/velocity", "particles/position", "particles/position",
                              ("/", "time")),
                       [("cgd-generate --restart", lambda w, x: [*restart, "-o", f"{w}/run"], [], "run")]),
        "series": (os.path.join("run", "series.h5"),
                   Target("time", "time", "time", "time", ("/", "rows")),
                   [("cgd-generate --restart", lambda w, x: [*restart, "-o", f"{w}/run"], [], "run")]),
        "filtered": ("filtered.h5",
                     Target("width_0/per_snapshot/numerator", "width_0/H", "width_0/slip", "bins/phi_edges",
                            ("width_0", "F")),
                     [("cgd-fit", lambda w, x: [f"{BIN}/cgd-fit", x, "--bootstrap", "20", "--no-cross-validation",
                                                "-o", f"{w}/out.h5"], ["out.h5", "out.h5.tmp"], None)]),
        "drag_model": ("model.h5",
                       Target("h/coefficients", "h/knots", "h/coefficients", "log_a/knots", ("/", "h_max")),
                       [("cgd-export", lambda w, x: [f"{BIN}/cgd-export", x, "--quiet", "-o", f"{w}/export"], ["export"],
                         None)]),
        "coarse_summary": (os.path.join("coarse", os.path.basename(summaries[0]), "summary.h5"),
                           Target(None, "@reference_slip_stderr", "@slip_over_ut", "@slip_stderr", ("/", "parcel_size")),
                           [("cgd-fit --parcel-fit", lambda w, x: [f"{BIN}/cgd-fit", "--parcel-fit", f"{w}/model.h5",
                                                                   *[f"{w}/coarse/{os.path.basename(d)}" for d in summaries],
                                                                   "-o", f"{w}/out.h5"], ["out.h5", "out.h5.tmp"], None)]),
    }
    pristine = os.path.join(tmp, "pristine")
    os.makedirs(pristine)
    for name in ("run", "coarse", "filtered.h5", "model.h5"):
        src = os.path.join(tmp, name)
        (shutil.copytree if os.path.isdir(src) else shutil.copy2)(src, os.path.join(pristine, name))

    def fresh(label):
        w = os.path.join(tmp, label)
        shutil.copytree(pristine, w)
        return w

    def check_tools(kind, damage, w, x, tools, must_refuse, show=True):
        outcome = []
        for name, argv, outputs, unchanged in tools:
            before = tree_digest(os.path.join(w, unchanged)) if unchanged else None
            status, text = run(argv(w, x))
            problems = []
            if status == "hang":
                problems.append("hang")
            elif status < 0:
                problems.append(f"signal {-status}")
            elif "Traceback" in text:
                problems.append("a traceback")
            elif must_refuse and status != 2:
                problems.append(f"exit {status}, expected 2")
            elif status == 2 and os.path.basename(x) not in text:
                problems.append("a message that does not name the file")
            if status != 0:
                problems += [f"wrote {o}" for o in outputs if os.path.exists(os.path.join(w, o))]
            if before is not None and status != 0 and tree_digest(os.path.join(w, unchanged)) != before:
                problems.append(f"changed {unchanged}/")
            line = next((l for l in text.splitlines() if "error" in l.lower() or x in l), text.strip()[:160])
            if problems:
                failures.append(f"{kind} / {damage} / {name}: {', '.join(problems)}: {text.strip()[-400:]}")
            outcome.append(f"{name}: {'FAIL ' + ', '.join(problems) if problems else 'exit ' + str(status)}")
            if status == 2:
                outcome[-1] += f" ({line.strip()[:150]})"
        if not show:
            return outcome
        # cgd-show: no traceback, no signal, one line (on stderr) when it refuses
        status, text = run([PY, os.path.join(SRC, "tools", "cgd-show"), x], stderr_only=True)
        bad = status == "hang" or status not in (0, 2) or "Traceback" in text or \
            (status == 2 and len([l for l in text.splitlines() if l.strip()]) != 1)
        if bad:
            failures.append(f"{kind} / {damage} / cgd-show: exit {status}: {text.strip()[-400:]}")
        outcome.append(f"cgd-show: {'FAIL' if bad else 'exit ' + str(status)}")
        return outcome

    # the undamaged inputs pass (so a refusal below is the damage's)
    for kind, (rel, target, tools) in kinds.items():
        w = fresh(f"ok_{kind}")
        for name, argv, outputs, unchanged in tools:
            status, text = run(argv(w, os.path.join(w, rel)))
            if status != 0:
                failures.append(f"{kind} undamaged / {name}: exit {status}: {text.strip()[-400:]}")
    print("undamaged inputs: " + ("read by every tool" if not failures else "FAIL"))

    count = 0
    for kind, (rel, target, tools) in kinds.items():
        for damage, apply in DAMAGES + UNSEEN_UNLESS_SEALED:
            if target.dataset is None and apply in (overwrite_array, random_bytes):
                continue  # a summary has no arrays
            count += 1
            w = fresh(f"d{count}")
            x = os.path.join(w, rel)
            if not apply(x, target, rng):
                failures.append(f"{kind} / {damage}: the damage did not apply")
                continue
            # a checkpoint edited with h5py fails its seal; the content checks behind it are tested on a resealed
            # copy too
            variants = [(damage, w, x)]
            if kind == "checkpoint" and apply not in (cut_short, overwrite_array, overwrite_metadata, random_bytes):
                w2 = fresh(f"d{count}_resealed")
                x2 = os.path.join(w2, rel)
                shutil.copy2(x, x2)
                cgd_seal.seal(x2)
                variants.append((damage + ", resealed", w2, x2))
            for label, wd, path in variants:
                must_refuse = (damage, apply) in DAMAGES or kind == "checkpoint"
                outcome = check_tools(kind, label, wd, path, tools, must_refuse, show=not label.endswith("resealed"))
                print(f"{kind:14s} {label:34s} " + "; ".join(outcome))
    # Two ranks: the checkpoint's content checks are one collective verdict and a snapshot refused on one rank
    # ends the job, so both refuse with exit 2 (no rank left waiting) and a restart still changes nothing.
    mpirun = shutil.which("mpirun")
    if mpirun:
        launcher = [mpirun, "--allow-run-as-root", "--oversubscribe", "-np", "2"]
        for kind, apply in (("checkpoint", nan_value), ("snapshot", nan_value)):
            rel, target, tools = kinds[kind]
            count += 1
            w = fresh(f"d{count}_mpi")
            x = os.path.join(w, rel)
            apply(x, target, rng)
            if kind == "checkpoint":
                cgd_seal.seal(x)  # past the seal, to the collective content check
            ranked = [(name + " at 2 ranks", lambda w, x, argv=argv: launcher + argv(w, x), outputs, unchanged)
                      for name, argv, outputs, unchanged in tools]
            outcome = check_tools(kind, "NaN value, 2 ranks", w, x, ranked, True, show=False)
            if kind == "checkpoint":  # the row is the file's, not the reading rank's slice's
                with h5py.File(x, "r") as f:
                    row = f["particles/position"].shape[0] // 2
                if f"row {row} column 0" not in "; ".join(outcome):
                    failures.append(f"checkpoint at 2 ranks: the message does not name row {row}: {outcome}")
            print(f"{kind:14s} {'NaN value, 2 ranks':34s} " + "; ".join(outcome))
    for f in failures:
        print("FAIL " + f)
    print(f"{count} damaged files, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
