"""mbcontact-prep: YAML scene + meshes -> one HDF5 scene file for the solver.

    mbcontact-prep SCENE.yaml [-o SCENE.h5] [--check] [-q]

Input format: docs/scene.md. Output layout: docs/scene-h5.md.

This process uses meshio, numpy, h5py and never imports petsc4py: the DMPlex
meshes are written by a subprocess (mbcontact._writemesh) because h5py's serial
HDF5 and PETSc's MPI HDF5 must not share a process. The subprocess creates the
file, then this process adds the /mbcontact metadata group.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

from . import __version__
from .bodies import (build_bodies, build_node_sets, couple_exclusions, face_labels, line_weights, nodes_of, pairs,
                     read_mesh, surface_faces)
from .cells import NODES, XDMF  # noqa: F401 (XDMF: the result file's cell names, docs)
from .scene import InputError, Time, load_yaml, parse_scene, warn

PROG = "mbcontact-prep"
FORMAT_VERSION = 1


class InternalError(Exception):
    """A failure that is not the user's input (e.g. the PETSc subprocess)."""


def main(argv=None):
    args = _arguments(argv)
    try:
        _run(args)
    except InputError as err:
        print(f"{PROG}: error: {args.scene}: {err}", file=sys.stderr)
        return 1
    except InternalError as err:
        print(f"{PROG}: error: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    return 0


def _arguments(argv):
    parser = argparse.ArgumentParser(
        prog=PROG, description="Convert a YAML scene and its meshes into the HDF5 scene "
                               "file read by the mbcontact solver.")
    parser.add_argument("scene", help="scene description (YAML, see docs/scene.md)")
    parser.add_argument("-o", "--output", help="output file (default: SCENE with suffix .h5)")
    parser.add_argument("--check", action="store_true", help="validate only, write nothing")
    parser.add_argument("-q", "--quiet", action="store_true", help="no summary on stdout")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    return parser.parse_args(argv)


def _run(args):
    output = args.output or os.path.splitext(args.scene)[0] + ".h5"
    if not args.check and not os.path.isdir(os.path.dirname(os.path.abspath(output))):
        raise InputError(f"cannot write {output}: no such directory")

    scene = parse_scene(load_yaml(args.scene), os.path.dirname(os.path.abspath(args.scene)))
    used = {b.mesh for b in scene.bodies}
    for name in scene.meshes:
        if name not in used:
            warn(f"meshes.{name} is not used by any body")
    meshes = {name: read_mesh(name, path, scene.extrude.get(name)) for name, path in scene.meshes.items() if name in used}
    bodies = build_bodies(scene, meshes)
    labels, face_counts = face_labels(scene, bodies)
    sets = build_node_sets(scene, bodies)
    exclude = couple_exclusions(scene, bodies, labels, sets)
    _reservoir_floors(scene, bodies)
    _uplift_extent(scene, bodies)
    nodal = _nodal_inputs(scene, bodies, sets)

    if not args.check:
        _write(output, scene, bodies, labels, face_counts, exclude, nodal)
    if not args.quiet:
        _print_summary(output, args.check, scene, bodies, face_counts, exclude, nodal)


def _print_summary(output, check_only, scene, bodies, face_counts, exclude, nodal=None):
    if scene.stages:
        print(f"{'checked' if check_only else 'wrote ' + output}: {len(scene.stages)} stages: "
              + ", ".join(f"{st.name} ({st.analysis.type}, t {st.start_time:g} to {st.analysis.final_time:g})"
                          for st in scene.stages))
    else:
        print(f"{'checked' if check_only else 'wrote ' + output}: {scene.analysis.type} analysis")
    for b, sb in zip(bodies, scene.bodies):
        kinds = ", ".join(f"{np.count_nonzero(b.types == t)} {t}" for t in np.unique(b.types)) if b.cell_type == "mixed" else b.cell_type
        nodes = f", {len(b.coords)} nodes" if len(b.coords) != b.num_vertices else ""
        print(f"  body {b.name}: {len(b.cells)} {kinds} cells, {b.num_vertices} vertices{nodes}"
              + (", rigid" if sb.rigid is not None else ""))
    for sid, (name, count) in enumerate(face_counts.items(), start=1):
        print(f"  surface {sid} {name}: {count} faces")
    for c in scene.couples:
        out = f", {len(exclude[scene.couples.index(c)])} master nodes out of contact" if c.exclude else ""
        joint = (f", bonded: cohesion={c.cohesion:g} tensile_strength={c.tensile_strength:g} "
                 f"mu_residual={c.mu_residual:g}" + (f" softening_displacement={c.softening:g}" if c.softening else "")) if c.cohesion > 0 else ""
        print(f"  couple k={c.k}: master {','.join(c.master)}, slave {','.join(c.slave)}, mu={c.mu:g}{', ' + c.sliding + ' sliding' if c.sliding else ''}{joint}{out}")
    if nodal:
        for i, rows in enumerate(nodal["dirichlet"]):
            if rows is not None:
                print(f"  dirichlet[{i}]: {len(rows)} nodes")
        for i, sp in enumerate(nodal["springs"]):
            print(f"  springs[{i}]: {len(sp[0])} {'node-to-node' if sp[1] is not None else 'node-to-ground'} springs")


def _reservoir_floors(scene, bodies):
    """An added mass without `bottom` takes the lowest point of its wetted surface as the
    reservoir's floor; one with a `bottom` above that point is refused (Westergaard's pressure is
    defined between the floor and the level)."""
    for i, m in enumerate(scene.added_mass):
        faces = surface_faces(m.surface, scene.surfaces[m.surface], bodies)
        low = min(bodies[b].coords[bodies[b].boundary_faces[index]][..., m.axis].min() for b, index in faces.items())
        if m.bottom is None:
            m.bottom = float(low)
        elif m.bottom > low + 1e-9 * max(1.0, abs(m.level - low)):
            raise InputError(f"added_mass[{i}].bottom: the surface '{m.surface}' reaches down to {low:g}, "
                             f"below the reservoir's floor {m.bottom:g}")
        if not m.level > m.bottom:
            raise InputError(f"added_mass[{i}].level: {m.level:g} is not above the reservoir's floor {m.bottom:g}")


def _uplift_extent(scene, bodies):
    """A couple's uplift acts where its master faces are, across the direction too: the joint's
    plane from the master faces' mean normal n, the lateral axis t = n x direction, and the master
    vertices' range along t (the slave side, a foundation reaching beyond the footprint, is loaded
    only under the joint), over all of them and per master body (its zone: the water's front moves
    in each zone on its own, so the monoliths of one base couple crack each as its own)."""
    for c in scene.couples:
        u = c.uplift
        if u is None:
            continue
        nrm, ts = np.zeros(3), {}
        for name in c.master:
            for b, index in surface_faces(name, scene.surfaces[name], bodies).items():
                body = bodies[b]
                for f in index:
                    nv = body.face_corners(body.boundary_faces[f:f + 1], body.boundary_nv[f:f + 1])[0]
                    x = body.coords[body.boundary_faces[f, :nv]]
                    nrm += 0.5 * sum(np.cross(x[k], x[(k + 1) % nv]) for k in range(nv))
                    ts.setdefault(b, []).append(x)
        nn = np.linalg.norm(nrm)
        if not nn > 0:
            raise InputError(f"{u['where']}: the master surfaces have no mean normal (a closed surface?): "
                             "the uplift needs a plane joint")
        nrm /= nn
        if abs(nrm @ u["direction"]) > 0.1:
            raise InputError(f"{u['where']}.direction: {list(u['direction'])} is not along the joint (the master "
                             f"faces' normal is [{nrm[0]:.3g}, {nrm[1]:.3g}, {nrm[2]:.3g}]): give the heel-to-toe "
                             "direction in the joint's plane")
        t = np.cross(nrm, u["direction"])
        t /= np.linalg.norm(t)
        zones = []
        for b in sorted(ts):
            y = (np.concatenate(ts[b]) - u["origin"]) @ t
            zones.append([y.min(), y.max(), [b]])
        merged, tol = [], 1e-9 * (max(z[1] for z in zones) - min(z[0] for z in zones) + u["length"])
        for lo, hi, bs in sorted(zones, key=lambda z: (z[0], z[1])):  # bodies side by side along the direction share a zone
            if merged and lo < merged[-1][1] - tol:
                merged[-1][1] = max(merged[-1][1], hi)
                merged[-1][2] += bs
            else:
                merged.append([lo, hi, bs])
        u["lateral"] = np.array([*t, min(z[0] for z in merged), max(z[1] for z in merged)])
        u["zones"] = np.array([z[:2] for z in merged])
        u["zone_of_body"] = np.full(len(bodies), -1)
        for i, z in enumerate(merged):
            u["zone_of_body"][z[2]] = i


def _nodal_inputs(scene, bodies, sets):
    """The node-based inputs resolved to (body, node) rows: Dirichlet conditions on nodes and
    bodies, nodal and line loads, initial conditions, springs; rigid bodies' reference points."""
    rigid = {i for i, b in enumerate(scene.bodies) if b.rigid is not None}
    out = {"dirichlet": [], "loads": [], "initial": {}, "springs": [], "rigid": {}}
    for i, d in enumerate(scene.dirichlet):
        where = f"dirichlet[{i}]"
        if d.body:
            b = [sb.name for sb in scene.bodies].index(d.body)
            out["dirichlet"].append(None if b in rigid else pairs({b: np.arange(len(bodies[b].coords))}))
            continue
        if d.surface:
            faces = surface_faces(d.surface, scene.surfaces[d.surface], bodies)
            hit = sorted(set(faces) & rigid)
            if hit:
                raise InputError(f"{where}.surface: '{d.surface}' lies on rigid body '{bodies[hit[0]].name}'; "
                                 "prescribe a rigid body's motion with `body:` (components x, y, z, rx, ry, rz)")
            out["dirichlet"].append(None)
            continue
        per_body = nodes_of(d.nodes, bodies, f"{where}.nodes", sets)
        hit = sorted(set(per_body) & rigid)
        if hit:
            raise InputError(f"{where}.nodes: {', '.join(d.nodes)} has nodes on rigid body '{bodies[hit[0]].name}'; "
                             "prescribe a rigid body's motion with `body:` (components x, y, z, rx, ry, rz)")
        out["dirichlet"].append(pairs(per_body))
    for i, load in enumerate(scene.loads):
        where = load.where or f"loads[{i}]"
        if load.kind == "nodal_force":
            rows = pairs(nodes_of(load.nodes, bodies, f"{where}.nodes", sets))
            out["loads"].append((rows, np.ones(len(rows))))
        elif load.kind == "line_force":
            per_body = line_weights(load.line, bodies, f"{where}.line")
            rows = pairs({b: n for b, (n, w) in per_body.items()})
            out["loads"].append((rows, np.concatenate([per_body[b][1] for b in sorted(per_body)])))
        else:
            out["loads"].append(None)
    for i, e in enumerate(scene.initial):
        where = f"initial[{i}]"
        if e.body:
            b = [sb.name for sb in scene.bodies].index(e.body)
            per_body = {b: np.arange(len(bodies[b].coords))}
        else:
            per_body = nodes_of(e.nodes, bodies, f"{where}.nodes", sets)
        for b, nodes in per_body.items():
            state = out["initial"].setdefault(b, {})
            for key in ("displacement", "velocity"):
                value = getattr(e, key)
                if value is None:
                    continue
                array = state.setdefault(key, np.zeros((len(bodies[b].coords), 3)))
                if isinstance(value, tuple):
                    field = bodies[b].mesh.point_data.get(value[1])
                    if field is None or field.shape[1] != 3:
                        have = ", ".join(f"{k} ({v.shape[1]} components)" for k, v in bodies[b].mesh.point_data.items()) or "none"
                        raise InputError(f"{where}.{key}.field: '{value[1]}' is no point field of 3 components of "
                                         f"{bodies[b].mesh.describe()} (point fields there: {have})")
                    inverse = np.full(len(bodies[b].coords), -1)
                    inverse[bodies[b].vertex_map[bodies[b].vertex_map >= 0]] = np.nonzero(bodies[b].vertex_map >= 0)[0]
                    array[nodes] = field[inverse[nodes]]
                else:
                    array[nodes] = value
    for i, sp in enumerate(scene.springs):
        where = f"springs[{i}]"
        rows = pairs(nodes_of(sp.nodes, bodies, f"{where}.nodes", sets))
        to = None
        if sp.to:
            other = pairs(nodes_of(sp.to, bodies, f"{where}.to", sets))
            xo = np.array([bodies[b].coords[v] for b, v in other])
            to = np.empty_like(rows)
            for r, (b, v) in enumerate(rows):
                k = np.argmin(np.linalg.norm(xo - bodies[b].coords[v], axis=1))
                if other[k][0] != b:
                    raise InputError(f"{where}.to: a spring joins two nodes of one body (body '{bodies[b].name}' to "
                                     f"'{bodies[other[k][0]].name}'): a spring between bodies would couple their "
                                     "factorizations; join the bodies by a couple, or give both ends to one body")
                if other[k][1] == v:
                    raise InputError(f"{where}.to: node {v} of body '{bodies[b].name}' is its own nearest node of `to`")
                to[r] = other[k]
            if len(np.unique(to, axis=0)) != len(to):
                raise InputError(f"{where}.to: two nodes of `nodes` share their nearest node of `to`; give sets of one node each, or of matching nodes")
        hit = sorted(set(rows[:, 0]) & rigid)
        if hit:
            raise InputError(f"{where}.nodes: a spring on rigid body '{bodies[hit[0]].name}': give its nodes to a "
                             "deformable body (a rigid body's DOFs are its reference point's)")
        out["springs"].append((rows, to))
    for i in rigid:
        b, spec = bodies[i], scene.bodies[i].rigid
        out["rigid"][i] = spec.get("reference", _centroid(b))
    return out


def _centroid(b):
    """The centroid of a body's cells (volume) or faces (a surface): each cell's corner centroid
    weighted by its size (corner tets' volumes, triangle fans' areas)."""
    from .cells import CORNER_TETS
    total, moment = 0.0, np.zeros(3)
    for t in np.unique(b.types):
        cells = b.cells[b.types == t]
        if t in ("tri3", "quad4"):
            nv = 3 if t == "tri3" else 4
            x = b.coords[cells[:, :nv]]
            centre = x.mean(axis=1)
            w = sum(0.5 * np.linalg.norm(np.cross(x[:, k] - centre, x[:, (k + 1) % nv] - centre), axis=1) for k in range(nv))
        else:
            ncorner = {"tet4": 4, "tet10": 4, "hex8": 8, "wedge6": 6, "pyr5": 5}[t]
            x = b.coords[cells[:, :ncorner]]
            centre = x.mean(axis=1)
            w = np.zeros(len(cells))
            for a, p, q, r in CORNER_TETS[t]:
                w += np.abs(np.linalg.det(np.stack([x[:, p] - x[:, a], x[:, q] - x[:, a], x[:, r] - x[:, a]], axis=1)))
        total += w.sum()
        moment += (w[:, None] * centre).sum(axis=0)
    return moment / total


# ---------------------------------------------------------------- writing

def _write(output, scene, bodies, labels, face_counts, exclude, nodal=None):
    """Write meshes (subprocess) then metadata into a temporary file, then rename."""
    folder = os.path.dirname(os.path.abspath(output))
    with tempfile.TemporaryDirectory(prefix="mbcontact-prep-") as tmp:
        npz = os.path.join(tmp, "bodies.npz")
        _save_bodies(npz, bodies, labels)
        partial = None
        try:
            fd, partial = tempfile.mkstemp(prefix=".mbcontact-prep-", suffix=".h5", dir=folder)
            os.close(fd)
            mask = os.umask(0)  # mkstemp makes it 0600: give it the mode of any new file
            os.umask(mask)
            os.chmod(partial, 0o666 & ~mask)
            _write_meshes(npz, partial)
            write_metadata(partial, scene, bodies, face_counts, labels, exclude, nodal)
            os.replace(partial, output)
        except OSError as err:
            raise InputError(f"cannot write {output}: {err.strerror or err}") from None
        finally:
            if partial and os.path.exists(partial):
                os.remove(partial)


def _save_bodies(path, bodies, labels):
    arrays = {"names": np.array([b.name for b in bodies])}
    for i, (body, values) in enumerate(zip(bodies, labels)):
        labelled = np.any(values != 0, axis=1)
        arrays[f"cells{i}"] = body.petsc_cells()
        arrays[f"types{i}"] = np.array([str(t) for t in body.types])
        arrays[f"dim{i}"] = np.array(body.dim)
        arrays[f"coords{i}"] = body.coords[:body.num_vertices]
        arrays[f"faces{i}"] = body.boundary_faces[labelled][:, :4].astype(np.int32)
        arrays[f"facenv{i}"] = np.where(body.boundary_nv[labelled] == 6, 3, body.boundary_nv[labelled]).astype(np.int32)
        arrays[f"labels{i}"] = values[labelled]
        arrays[f"faceidx{i}"] = np.nonzero(labelled)[0].astype(np.int64)  # a surface body's faces are its cells
    np.savez(path, **arrays)


def _write_meshes(npz, h5):
    python = os.environ.get("MBCONTACT_PYTHON", sys.executable)
    package_root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [package_root, env.get("PYTHONPATH")]))
    try:
        done = subprocess.run([python, "-m", "mbcontact._writemesh", npz, h5],
                              env=env, capture_output=True, text=True)
    except OSError as err:
        raise InternalError(f"cannot run {python} to write the meshes: {err}") from None
    if done.returncode != 0:
        raise InternalError(f"writing the meshes with petsc4py ({python}) failed:\n"
                            + done.stderr.strip()[:6000])


def _scheme(a):
    """A dynamic analysis' time integrator beyond Newmark's (absent: Newmark with its beta, gamma)."""
    if a.scheme == "newmark":
        return {}
    return dict(scheme=a.scheme, alpha_m=a.alpha_m, alpha_f=a.alpha_f,
                **({"hht_alpha": a.alpha} if a.scheme == "hht" else {"rho_inf": a.rho_inf}))


def write_metadata(path, scene, bodies, face_counts, labels=None, exclude=None, nodal=None):
    """Add the /mbcontact group (docs/scene-h5.md) to an existing HDF5 file."""
    import h5py

    surface_ids = {name: i + 1 for i, name in enumerate(scene.surfaces)}
    tables = []  # time function tables, in index order

    def time_function(time):
        if time.kind != "table":
            return -1
        tables.append(time.table)
        return len(tables) - 1

    with h5py.File(path, "a") as f:
        root = f.create_group("mbcontact")
        _attrs(root, format_version=FORMAT_VERSION, title=scene.title)
        a = scene.analysis
        _attrs(root.create_group("analysis"), type=a.type, dt=a.dt, final_time=a.final_time,
               newmark_beta=a.newmark_beta, newmark_gamma=a.newmark_gamma, mass=a.mass, **_scheme(a),
               **(dict(modes=a.modes, tie=int(a.tie)) if a.type == "modal" else {}))
        _list(root, "surfaces", face_counts.items(), lambda g, item: _attrs(
            g, name=item[0], id=surface_ids[item[0]], num_faces=item[1]))
        def body(g, item):
            i, (sb, b) = item
            _attrs(g, name=sb.name, cell_type=b.cell_type, num_cells=len(b.cells),
                   num_vertices=b.num_vertices, **sb.material,
                   **({"num_nodes": len(b.coords)} if len(b.coords) != b.num_vertices else {}),
                   **({"element": sb.element} if sb.element else {}),
                   **({"massless": 1} if sb.massless else {}))
            if b.cell_type == "mixed":  # each cell's type, in the scene's cell order
                codes = {"tet4": 0, "hex8": 1, "wedge6": 2, "pyr5": 3}
                g.create_dataset("cell_types", data=np.array([codes[t] for t in b.types], dtype=np.int32))
            if b.cell_type == "surface":
                g.create_dataset("cell_types", data=np.array([4 if t == "tri3" else 5 for t in b.types], dtype=np.int32))
            if len(b.coords) != b.num_vertices:  # tet10: each midside node's edge (its corners) and position
                g.create_dataset("midside", data=b.midside().astype(np.int32))
                g.create_dataset("midside_coords", data=b.coords[b.num_vertices:].astype(np.float64))
            if sb.rigid is not None:
                r = sb.rigid
                _attrs(g, rigid=1, reference=nodal["rigid"][i] if nodal else np.zeros(3), rigid_mass=r.get("mass", 0.0),
                       rigid_inertia=r["inertia"].ravel() if "inertia" in r else np.zeros(9))
            if nodal and i in nodal["initial"]:
                for key, array in nodal["initial"][i].items():
                    g.create_dataset(f"initial_{key}", data=array.astype(np.float64))

        _list(root, "bodies", enumerate(zip(scene.bodies, bodies)), body)
        def side_faces(c, column):  # faces of each body on one side of couple c: the edge weights of the decomposition
            if labels is None:
                return np.zeros(len(bodies), dtype=np.int32)
            return np.array([np.count_nonzero(lab[:, column] == c.k) for lab in labels], dtype=np.int32)

        def couple(g, item):
            i, c = item
            _attrs(g, k=c.k, mu=c.mu, master=",".join(c.master), slave=",".join(c.slave),
                   master_faces=side_faces(c, 1), slave_faces=side_faces(c, 2))
            if c.sliding:
                _attrs(g, sliding=c.sliding)
            if c.cohesion > 0:  # the joint law, only on bonded couples (older scenes' files stay as they were)
                _attrs(g, cohesion=c.cohesion, tensile_strength=c.tensile_strength, mu_residual=c.mu_residual)
                if c.softening > 0:
                    _attrs(g, softening_displacement=c.softening)
            if exclude is not None and len(exclude[i]):  # (body, vertex) of the master nodes out of contact
                g.create_dataset("exclude", data=exclude[i].astype(np.int32))
            u = c.uplift
            if u is not None:  # the law's or the table's keys, settled by the parse (docs/scene-h5.md)
                table = u["table"]
                _attrs(g, uplift=1, uplift_origin=u["origin"], uplift_direction=u["direction"],
                       uplift_length=u["length"], uplift_unit_weight=u["unit_weight"],
                       uplift_heel_head=u.get("heel_head", 0.0), uplift_tail_head=u.get("tail_head", 0.0),
                       uplift_drain=u.get("drain", -1.0), uplift_efficiency=u.get("drain_efficiency", 0.0),
                       uplift_penetration=int(u["penetration"]), uplift_level=u["level"],
                       uplift_threshold=u["threshold"], uplift_axis=int(u["axis"]),
                       uplift_table_rows=0 if table is None else len(table),
                       uplift_lateral=u.get("lateral", np.array([0, 0, 0, -1e300, 1e300])))
                if table is not None:
                    g.create_dataset("uplift_table", data=np.asarray(table, dtype=np.float64))
                zones = u.get("zones", np.array([[-1e300, 1e300]]))
                _attrs(g, uplift_zones=len(zones))
                g.create_dataset("uplift_zone_range", data=np.asarray(zones, dtype=np.float64))
                g.create_dataset("uplift_zone_body", data=np.asarray(u.get("zone_of_body", np.zeros(len(bodies))), dtype=np.float64))

        _list(root, "couples", enumerate(scene.couples), couple)

        dirichlet = []
        names = [b.name for b in scene.bodies]
        for i, d in enumerate(scene.dirichlet):
            index = time_function(d.time)
            rows = nodal["dirichlet"][i] if nodal else None
            label = d.surface or (f"body:{d.body}" if d.body else "nodes:" + "+".join(d.nodes).replace(",", " "))[:200]
            where = dict(surface=d.surface, surface_id=surface_ids[d.surface]) if d.surface else \
                dict(surface=label, surface_id=-1, **({"body": names.index(d.body)} if d.body and rows is None else {}))
            dirichlet += [(dict(**where, component=comp, value=d.value, time=d.time.kind, time_function=index), rows)
                          for comp in d.components]

        def dirichlet_entry(g, item):
            attrs, rows = item
            _attrs(g, **attrs)
            if rows is not None:  # (body, node) of each prescribed node
                g.create_dataset("nodes", data=rows.astype(np.int32))

        _list(root, "dirichlet", dirichlet, dirichlet_entry)

        def load(g, item):
            i, load = item
            if nodal and nodal["loads"][i] is not None:  # nodal and line forces: (body, node), weight
                rows, weights = nodal["loads"][i]
                g.create_dataset("nodes", data=rows.astype(np.int32))
                g.create_dataset("weights", data=np.asarray(weights, dtype=np.float64))
            _attrs(g, kind=load.kind, vector=load.vector, value=load.value, surface=load.surface,
                   surface_id=surface_ids.get(load.surface, -1), bodies=",".join(load.bodies),
                   time=load.time.kind, time_function=time_function(load.time), stage=load.stage,
                   **(dict(level=load.level, unit_weight=load.unit_weight, axis=load.axis)
                      if load.kind == "hydrostatic" else {}),
                   **(dict(velocity_function=time_function(Time("table", load.velocity)),
                           displacement_function=time_function(Time("table", load.displacement)))
                      if load.kind == "ground_acceleration" else {}),
                   **(dict(couple=load.couple, side=load.side) if load.kind == "uplift" else {}))

        _list(root, "loads", enumerate(scene.loads), load)

        def spring(g, item):
            rows, to = item[1]
            _attrs(g, stiffness=item[0].stiffness, damping=item[0].damping)
            g.create_dataset("nodes", data=rows.astype(np.int32))
            if to is not None:
                g.create_dataset("to", data=to.astype(np.int32))

        _list(root, "springs", zip(scene.springs, nodal["springs"] if nodal else []), spring)
        _list(root, "added_mass", scene.added_mass, lambda g, m: _attrs(
            g, model="westergaard", surface=m.surface, surface_id=surface_ids[m.surface], density=m.density,
            level=m.level, bottom=m.bottom, axis=m.axis))
        _list(root, "absorbing", scene.absorbing, lambda g, x: _attrs(
            g, surface=x.surface, surface_id=surface_ids[x.surface], input=x.input))
        _list(root, "stages", scene.stages, lambda g, st: _attrs(
            g, name=st.name, type=st.analysis.type, start_time=st.start_time, dt=st.analysis.dt,
            final_time=st.analysis.final_time, newmark_beta=st.analysis.newmark_beta,
            newmark_gamma=st.analysis.newmark_gamma, mass=st.analysis.mass, **_scheme(st.analysis)))
        _list(root, "time_functions", tables, lambda g, table: (
            _attrs(g, kind="table"), g.create_dataset("table", data=table.astype(np.float64))))

        out = scene.output
        group = root.create_group("output")
        _attrs(group, every=out.every, fields=",".join(out.fields), energy=int(out.energy),
               points_count=len(out.points))
        _list(group, "points", out.points, lambda g, p: _attrs(g, name=p.name, x=p.x, body=p.body))


def _list(parent, name, items, fill):
    """Subgroups 0, 1, ... filled by fill(group, item), and a `count` attribute."""
    group = parent.create_group(name)
    count = 0
    for count, item in enumerate(items, start=1):
        fill(group.create_group(str(count - 1)), item)
    _attrs(group, count=count)
    return group


def _attrs(group, **values):
    """Strings as fixed-length ASCII, ints as int32, reals and vectors as float64."""
    for key, value in values.items():
        if isinstance(value, str):
            value = np.bytes_(value.encode("ascii"))
        elif isinstance(value, (bool, int, np.integer)):
            value = np.int32(value)
        else:
            value = np.asarray(value, dtype=np.float64)
        group.attrs[key] = value


if __name__ == "__main__":
    sys.exit(main())


def prepare(outdir, name, scene):
    """Writes scene (a dict) as OUTDIR/NAME.yaml and makes OUTDIR/NAME.h5 from it with
    mbcontact-prep (a subprocess, as the command line would); returns the .h5 path. For the
    scene-building scripts of meshes/ and bench/."""
    import yaml

    yml, h5 = os.path.join(outdir, f"{name}.yaml"), os.path.join(outdir, f"{name}.h5")
    with open(yml, "w") as f:
        yaml.safe_dump(scene, f, sort_keys=False)
    prep = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "mbcontact-prep")
    if os.path.isfile(prep):  # the source tree
        cmd = [prep]
    else:  # an installed package (pip install .): this interpreter, this package
        cmd = [sys.executable, "-c", "import sys; from mbcontact.prep import main; sys.exit(main())"]
    subprocess.run([*cmd, yml, "-o", h5, "-q"], check=True)
    return h5
