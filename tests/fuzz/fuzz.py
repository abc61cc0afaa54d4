#!/usr/bin/python3
"""Fuzzer of mbcontact's inputs: scene .h5 files, YAML scenes (through mbcontact-prep) and FCLIB
files. Each mutant is one small change of a valid input, made by random.Random(f"{seed}:{kind}:{i}"),
so `fuzz.py --seed S --kind K --only I --keep DIR` rebuilds mutant I exactly.

Every mutant runs with a timeout and is classed:
  rejected  non-zero exit with one "error:" message and no crash report (what we want for bad input)
  accepted  exit 0 (or 2, "not converged", for FCLIB) with finite, bounded results (a harmless change)
  crash     a signal, a sanitizer report, a PETSc error dump or a Python traceback
  hang      the timeout
  garbage   exit 0 with non-finite or absurd results (|u| beyond 10 model sizes)
The first three failure classes make the exit status 1.

    /usr/bin/python3 tests/fuzz/fuzz.py -n 200 --seed 1 [--kind h5,yaml,fclib] [-j 2]
"""
import argparse
import concurrent.futures
import copy
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "python"))
from mbcontact import meshgen  # noqa: E402

BUILD = os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build"))
SOLVER = os.path.join(BUILD, "mbcontact")
PREP = os.path.join(ROOT, "python", "mbcontact-prep")
PYTHON = "/usr/bin/python3"
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", PYTHONPATH=os.path.join(ROOT, "python"))
CRASH_WORDS = ("AddressSanitizer", "runtime error:", "LeakSanitizer", "Segmentation", "Caught signal",
               "core dumped", "Traceback (most recent call last)", "------------------------------------",
               "buffer overflow", "double free", "corrupted", "malloc():", "free():", "Aborted")

INTS = [0, 1, -1, 2, 3, 7, -2, 2**31 - 1, -2**31, 2**31, 2**40, -2**40, 10**9, 255, 256]
REALS = [0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, -1e-300, 1e300, -1e300, 1e308, 1e20, 1e-9,
         math.inf, -math.inf, math.nan, 2.0**31, 1e-308]


# ---------------------------------------------------------------- base inputs
def scene_one(d):
    """One hex8 column, fixed at the base, under gravity (static)."""
    meshgen.box(os.path.join(d, "one.msh"), (0, 0, 0), (1, 1, 2), n=(1, 1, 2), cell="hex8", volume_name="b1")
    return {"title": "fuzz one", "meshes": {"m": "one.msh"},
            "bodies": {"b1": {"mesh": "m", "regions": ["b1"], "material": {"E": 1e9, "nu": 0.2, "density": 1000.0}}},
            "dirichlet": [{"surface": "zmin", "components": "all"}],
            "loads": [{"kind": "gravity", "vector": [0, 0, -9.81]}, {"kind": "pressure", "surface": "zmax", "value": 1e5}],
            "output": {"every": 1, "points": {"top": {"x": [0.5, 0.5, 2.0]}}}}


def scene_two(d):
    """A tet4 block resting on a fixed hex8 block, one couple with friction (static)."""
    meshgen.boxes(os.path.join(d, "two.msh"), [dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(1, 1, 1), cell="hex8", name="lo"),
                                               dict(lo=(0, 0, 1), hi=(1, 1, 2), n=(1, 1, 1), cell="tet4", name="up")])
    return {"meshes": {"m": "two.msh"},
            "bodies": {b: {"mesh": "m", "regions": [b], "material": {"E": 1e9, "nu": 0.25, "density": 2000.0}} for b in ("lo", "up")},
            "couples": [{"k": 1, "master": "lo_zmax", "slave": "up_zmin", "mu": 0.5}],
            "dirichlet": [{"surface": "lo_zmin", "components": "all"}],
            "loads": [{"kind": "gravity", "vector": [0, 0, -9.81]}]}


def run(cmd, timeout):
    t0 = time.time()
    for attempt in range(5):
        try:
            r = subprocess.run(cmd, capture_output=True, text=True, env=ENV, timeout=timeout, errors="replace")
            return r.returncode, r.stdout + r.stderr, time.time() - t0
        except subprocess.TimeoutExpired:
            return None, "", time.time() - t0
        except OSError:  # the binary being relinked: not the mutant's fault
            time.sleep(2)
    raise RuntimeError(f"cannot run {cmd[0]}")


def write_matrix(g, a, fmt):
    """FCLIB matrix group from dense a: fmt "csr" (nz = -2), "csc" (-1) or "triplet" (nz >= 0)."""
    import scipy.sparse as sp
    m, n = a.shape
    if fmt == "triplet":
        c = sp.coo_matrix(a)
        p, i, x, nz = c.col, c.row, c.data, c.nnz
    else:
        c = sp.csr_matrix(a) if fmt == "csr" else sp.csc_matrix(a)
        p, i, x, nz = c.indptr, c.indices, c.data, -2 if fmt == "csr" else -1
    for k, v in (("m", [m]), ("n", [n]), ("nz", [nz]), ("nzmax", [len(x)]), ("p", p), ("i", i)):
        g[k] = np.asarray(v, dtype=np.int32)
    g["x"] = np.asarray(x, dtype=float)


def write_global_fclib(path, nc=2):
    """A small FCLIB global problem M v = H r + f, u = H^T v + w: M SPD tridiagonal (CSR), H with
    two entries per column (triplets), so W = H^T M^-1 H has a positive normal diagonal."""
    n = 3 * nc + 3
    M = 4 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    H = np.zeros((n, 3 * nc))
    for j in range(3 * nc):
        H[j, j], H[j + 3, j] = 1.0, -0.5
    with h5py.File(path, "w") as f:
        g = f.create_group("fclib_global")
        g["spacedim"] = np.array([3], dtype=np.int32)
        write_matrix(g.create_group("M"), M, "csr")
        write_matrix(g.create_group("H"), H, "triplet")
        v = g.create_group("vectors")
        v["f"] = np.linspace(-1, 1, n)
        v["w"] = np.tile([0.1, 0.0, 0.0], nc)
        v["mu"] = np.full(nc, 0.3)


def make_bases(d):
    """Writes the base YAML scenes, their .h5 files and two FCLIB problems into d; returns their paths."""
    bases = {"yaml": [], "h5": [], "fclib": []}
    for name, build in (("one", scene_one), ("two", scene_two)):
        doc = build(d)
        yml = os.path.join(d, f"{name}.yaml")
        with open(yml, "w") as f:
            yaml.safe_dump(doc, f, sort_keys=False)
        h5 = os.path.join(d, f"{name}.h5")
        rc, out, _ = run([PYTHON, PREP, yml, "-o", h5, "-q"], 120)
        assert rc == 0, out
        bases["yaml"].append(yml)
        bases["h5"].append(h5)
    loc = os.path.join(d, "two_local.hdf5")  # the solver's own multiplier problem (local, CSR)
    rc, out, _ = run([SOLVER, "-scene", bases["h5"][1], "-mbc_output", os.path.join(d, "two_base"), "-mbc_fclib_write", loc], 120)
    assert rc == 0, out
    glob = os.path.join(d, "global.hdf5")
    write_global_fclib(glob)
    rc, out, _ = run([SOLVER, "-fclib", glob], 120)
    assert rc == 0, out
    bases["fclib"] = [glob, loc]
    return bases


# ---------------------------------------------------------------- HDF5 mutators
def h5_objects(path):
    """[(kind, name, attr)] of every dataset and every attribute in the file."""
    objs = []
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                objs.append(("dset", name, None))
            else:
                objs.append(("group", name, None))
            for a in obj.attrs:
                objs.append(("attr", name, a))
        f.visititems(visit)
        for a in f.attrs:
            objs.append(("attr", "/", a))
    return objs


def mutate_value(rng, a):
    """A copy of array a with one change: an interesting value, a neighbour, a shuffle, a scale."""
    a = np.array(a)
    if a.dtype.kind in "SUO":
        choice = rng.choice([b"", b"x" * rng.choice([1, 300, 5000]), b"static", b"dynamic", b"table", b"-1", b"\xff\xfe", b"a,b", b"b1"])
        return np.bytes_(choice) if a.shape == () else np.array([choice] * max(a.size, 1))
    flat = a.reshape(-1).copy()
    if flat.size == 0:
        return np.zeros(rng.randint(1, 4), dtype=a.dtype if a.dtype.kind in "iuf" else float)
    how = rng.random()
    i = rng.randrange(flat.size)
    if how < 0.45:
        v = rng.choice(INTS) if flat.dtype.kind in "iu" else rng.choice(REALS + INTS)
        if flat.dtype.kind in "iu":
            info = np.iinfo(flat.dtype)
            v = max(min(v, info.max), info.min)
        flat[i] = v
    elif how < 0.6:
        flat[i] = flat[i] + rng.choice([-1, 1]) if flat.dtype.kind in "iu" else flat[i] * rng.choice([-1.0, 1e-9, 1e9, 1.0000001])
    elif how < 0.7:
        flat = flat[::-1].copy()
    elif how < 0.8:
        perm = list(range(flat.size))
        rng.shuffle(perm)
        flat = flat[perm]
    elif how < 0.9:
        j = rng.randrange(flat.size)
        flat[i], flat[j] = flat[j], flat[i]
    else:
        if flat.dtype.kind == "f":
            flat *= rng.choice([1e300, -1.0, 0.0, 1e-300])
        else:
            flat += rng.choice([1, -1, 1000])
    return flat.reshape(a.shape)


def mutate_h5(rng, path):
    """One change of the HDF5 file at path (values, shape, dtype, removal, truncation, bytes);
    returns a description."""
    how = rng.random()
    if how < 0.05:  # cut the file
        size = os.path.getsize(path)
        cut = rng.randrange(size)
        with open(path, "r+b") as f:
            f.truncate(cut)
        return f"truncate file to {cut} of {size} bytes"
    if how < 0.1:  # flip bytes
        size = os.path.getsize(path)
        with open(path, "r+b") as f:
            offs = [rng.randrange(size) for _ in range(rng.randint(1, 8))]
            for o in offs:
                f.seek(o)
                b = f.read(1)
                f.seek(o)
                f.write(bytes([(b[0] ^ (1 << rng.randrange(8))) if b else 0]))
        return f"flip bits at {offs}"
    objs = h5_objects(path)
    # most of the interest is in the meshes and the lists: bias towards datasets and attributes
    kind, name, attr = rng.choice(objs)
    with h5py.File(path, "a") as f:
        if kind == "group":
            if rng.random() < 0.5 and name not in ("", "/"):
                del f[name]
                return f"remove group {name}"
            kind = "attr"
            attrs = list(f[name].attrs)
            if not attrs:
                f[name].attrs["count"] = rng.choice(INTS)
                return f"add attribute {name}@count"
            attr = rng.choice(attrs)
        if kind == "attr":
            obj = f[name]
            old = obj.attrs[attr]
            r = rng.random()
            if r < 0.12:
                del obj.attrs[attr]
                return f"remove attribute {name}@{attr}"
            if r < 0.24:  # another type
                new = rng.choice([np.float64(1.5), np.int64(2**40), np.int32(-1), np.bytes_("x"), np.array([1.0, 2.0]), np.array([], dtype=float)])
                obj.attrs[attr] = new
                return f"attribute {name}@{attr} = {new!r} (was {old!r})"
            new = mutate_value(rng, old)
            try:
                obj.attrs[attr] = new.astype(np.array(old).dtype) if np.array(old).dtype.kind in "iuf" else new
            except (OverflowError, ValueError, TypeError):
                obj.attrs[attr] = new
            return f"attribute {name}@{attr}: {np.array(old).ravel()[:4]} -> {np.array(new).ravel()[:4]}"
        d = f[name]
        data = d[...]
        r = rng.random()
        if r < 0.08:
            del f[name]
            return f"remove dataset {name}"
        if r < 0.2:  # shorter or longer
            n = data.shape[0] if data.ndim else 1
            m = rng.choice([0, 1, max(n - 1, 0), n + 1, n // 2, 2 * n])
            new = np.resize(data, (m,) + data.shape[1:]) if data.ndim else data
            del f[name]
            f[name] = new
            return f"resize dataset {name}: {n} -> {m} rows"
        if r < 0.28:  # another shape
            new = data.reshape(-1)
            shape = rng.choice([(new.size,), (1, new.size), (new.size // 2, 2) if new.size % 2 == 0 else (new.size, 1, 1)])
            del f[name]
            f[name] = new.reshape(shape)
            return f"reshape dataset {name}: {data.shape} -> {shape}"
        if r < 0.36:  # another dtype
            t = rng.choice([np.float64, np.int64, np.int8, np.float32, np.uint32])
            try:
                new = data.astype(t)
            except (ValueError, OverflowError):
                new = np.zeros(data.shape, t)
            del f[name]
            f[name] = new
            return f"dtype of {name}: {data.dtype} -> {np.dtype(t)}"
        new = mutate_value(rng, data)
        d[...] = new.astype(data.dtype) if data.dtype.kind in "iuf" and new.dtype != data.dtype else new
        diff = np.flatnonzero(np.array(new).reshape(-1) != np.array(data).reshape(-1))
        return f"values of {name}: {len(diff)} changed, first at {diff[:1]}"


# ---------------------------------------------------------------- YAML mutator
def leaves(doc, path=()):
    out = [path]
    if isinstance(doc, dict):
        for k, v in doc.items():
            out += leaves(v, path + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out += leaves(v, path + (i,))
    return out


def mutate_yaml(rng, doc):
    doc = copy.deepcopy(doc)
    path = rng.choice(leaves(doc)[1:])
    parent = doc
    for p in path[:-1]:
        parent = parent[p]
    key = path[-1]
    r = rng.random()
    if r < 0.15 and isinstance(parent, dict):
        del parent[key]
        return doc, f"remove {'.'.join(map(str, path))}"
    if r < 0.2 and isinstance(parent, dict):
        parent[key + "_typo" if isinstance(key, str) else key] = 1
        return doc, f"unknown key beside {'.'.join(map(str, path))}"
    new = rng.choice(INTS + REALS + ["", "x" * rng.choice([1, 300, 5000, 10**6]), None, [], {}, [1, 2], "zmax", "b1", "table", True])
    parent[key] = new
    return doc, f"{'.'.join(map(str, path))} = {str(new)[:40]}"


# ---------------------------------------------------------------- results check
def results_ok(prefix, size):
    """Finite numbers everywhere in the result file, displacements within 10 model sizes."""
    path = prefix + ".h5"
    if not os.path.exists(path):
        return True, ""
    bad = []
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and obj.dtype.kind == "f":
                a = obj[...]
                if not np.all(np.isfinite(a)):
                    bad.append(f"{name} not finite")
                elif "displacement" in name and a.size and np.abs(a).max() > 10 * size:
                    bad.append(f"{name}: |u| = {np.abs(a).max():.3g} m in a {size:g} m model")
        f.visititems(visit)
    return not bad, "; ".join(bad)


def classify(rc, out, garbage=""):
    if rc is None:
        return "hang"
    if rc < 0 or any(w in out for w in CRASH_WORDS):
        return "crash"
    if rc == 0 or rc == 2:
        return "garbage" if garbage else "accepted"
    if "error:" in out:
        return "rejected"
    return "crash"  # a non-zero exit without a message


def one(kind, seed, i, bases, workdir, timeout, keep=None):
    rng = random.Random(f"{seed}:{kind}:{i}")
    d = tempfile.mkdtemp(dir=workdir)
    try:
        if kind == "h5":
            base = rng.choice(bases["h5"])
            path = os.path.join(d, "m.h5")
            shutil.copy(base, path)
            try:
                desc = mutate_h5(rng, path)
            except Exception as e:  # h5py refused the change: the file stays valid
                desc = f"(mutation refused: {type(e).__name__})"
            prefix = os.path.join(d, "r")
            rc, out, t = run([SOLVER, "-scene", path, "-mbc_output", prefix], timeout)
            ok, why = results_ok(prefix, 2.0) if rc == 0 else (True, "")
            cls = classify(rc, out, "" if ok else why)
        elif kind == "yaml":
            base = rng.choice(bases["yaml"])
            with open(base) as f:
                doc = yaml.safe_load(f)
            doc, desc = mutate_yaml(rng, doc)
            yml = os.path.join(d, "m.yaml")
            with open(yml, "w") as f:
                yaml.safe_dump(doc, f, sort_keys=False)
            for m in ("one.msh", "two.msh"):
                shutil.copy(os.path.join(os.path.dirname(base), m), d)
            h5 = os.path.join(d, "m.h5")
            rc, out, t = run([PYTHON, PREP, yml, "-o", h5, "-q"], timeout)
            cls = classify(rc, out)
            if rc == 0 and cls == "accepted":
                prefix = os.path.join(d, "r")
                rc, out2, t2 = run([SOLVER, "-scene", h5, "-mbc_output", prefix], timeout)
                out, t = out + out2, t + t2
                ok, why = results_ok(prefix, 2.0) if rc == 0 else (True, "")
                cls = classify(rc, out, "" if ok else why)
        else:
            base = rng.choice(bases["fclib"])
            path = os.path.join(d, "m.hdf5")
            shutil.copy(base, path)
            try:
                desc = mutate_h5(rng, path)
            except Exception as e:
                desc = f"(mutation refused: {type(e).__name__})"
            rc, out, t = run([SOLVER, "-fclib", path], timeout)
            garbage = ""
            merit = re.search(r"FCLIB merit (\S+)", out)
            if rc in (0, 2) and not (merit and math.isfinite(float(merit.group(1)))):  # the result's merit, not the
                garbage = "FCLIB result: " + out.strip().splitlines()[-1][:120]       # word NANORINF of a reason
            cls = classify(rc, out, garbage)
        if keep:
            os.makedirs(keep, exist_ok=True)
            for f in os.listdir(d):
                shutil.copy(os.path.join(d, f), keep)
        return dict(kind=kind, index=i, base=os.path.basename(base), mutation=desc, cls=cls, rc=rc, seconds=round(t, 2),
                    output=out.strip()[-600:])
    finally:
        shutil.rmtree(d, ignore_errors=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-n", type=int, default=100, help="mutants per kind")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--kind", default="h5,yaml,fclib")
    ap.add_argument("--only", type=int, help="run mutant ONLY of each kind (to reproduce it)")
    ap.add_argument("--keep", help="with --only: copy the mutant's files to this folder")
    ap.add_argument("-j", type=int, default=2, help="mutants run at once")
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds per run (a hang)")
    ap.add_argument("-v", action="store_true", help="print every mutant")
    args = ap.parse_args(argv)
    kinds = args.kind.split(",")
    workdir = tempfile.mkdtemp(prefix="mbc-fuzz-")
    try:
        bases = make_bases(workdir)
        jobs = [(k, i) for i in ([args.only] if args.only is not None else range(args.n)) for k in kinds]
        counts, failures = {}, []
        t0 = time.time()
        with concurrent.futures.ThreadPoolExecutor(args.j) as ex:
            for r in ex.map(lambda job: one(job[0], args.seed, job[1], bases, workdir, args.timeout, args.keep), jobs):
                counts.setdefault(r["kind"], {}).setdefault(r["cls"], 0)
                counts[r["kind"]][r["cls"]] += 1
                if args.v or args.only is not None:
                    print(f"{r['kind']} {r['index']} [{r['base']}] {r['mutation']}: {r['cls']} (exit {r['rc']}, {r['seconds']} s)"
                          + ("\n    " + r["output"].replace("\n", "\n    ") if args.only is not None or r["cls"] not in ("rejected", "accepted") else ""))
                if r["cls"] in ("crash", "hang", "garbage"):
                    failures.append(r)
        print(f"seed {args.seed}, {len(jobs)} mutants in {time.time() - t0:.0f} s")
        for k in kinds:
            c = counts.get(k, {})
            print(f"  {k:6s} " + ", ".join(f"{c.get(x, 0)} {x}" for x in ("rejected", "accepted", "crash", "hang", "garbage")))
        for r in failures:
            print(f"FAIL {r['cls']}: --seed {args.seed} --kind {r['kind']} --only {r['index']}: {r['mutation']}\n    "
                  + r["output"].replace("\n", "\n    "))
        return 1 if failures else 0
    finally:
        shutil.rmtree(workdir, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
