"""Readers for mbcontact's result files (h5py only: never import petsc4py beside it)."""
import csv

import numpy as np


def read_csv(path):
    """A CSV written by the solver as a dict of column name -> numpy array."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, data = rows[0], np.array(rows[1:], dtype=float).reshape(-1, len(rows[0]))
    return {name: data[:, i] for i, name in enumerate(header)}


def _dataset(group, prefix):
    names = [n for n in group if n.startswith(prefix)]
    if not names:
        raise KeyError(f"no dataset named {prefix}* in {group.name}")
    return group[names[0]]


def read_body(path, step=-1):
    """Vertices, cells, displacement (nv, 3) and stress (nc, 6) of one body's result file at an output step."""
    import h5py

    with h5py.File(path, "r") as f:
        out = {"vertices": f["geometry/vertices"][...], "cells": f["viz/topology/cells"][...]}
        if "vertex_fields" in f:
            out["displacement"] = _dataset(f["vertex_fields"], "displacement")[step]
            out["num_steps"] = _dataset(f["vertex_fields"], "displacement").shape[0]
        if "cell_fields" in f:
            out["stress"] = _dataset(f["cell_fields"], "stress")[step]
    return out
