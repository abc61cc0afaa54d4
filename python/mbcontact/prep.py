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
from .bodies import build_bodies, couple_exclusions, face_labels, read_mesh, surface_faces
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
    meshes = {name: read_mesh(name, path) for name, path in scene.meshes.items() if name in used}
    bodies = build_bodies(scene, meshes)
    labels, face_counts = face_labels(scene, bodies)
    exclude = couple_exclusions(scene, bodies, labels)
    _reservoir_floors(scene, bodies)

    if not args.check:
        _write(output, scene, bodies, labels, face_counts, exclude)
    if not args.quiet:
        _print_summary(output, args.check, scene, bodies, face_counts, exclude)


def _print_summary(output, check_only, scene, bodies, face_counts, exclude):
    if scene.stages:
        print(f"{'checked' if check_only else 'wrote ' + output}: {len(scene.stages)} stages: "
              + ", ".join(f"{st.name} ({st.analysis.type}, t {st.start_time:g} to {st.analysis.final_time:g})"
                          for st in scene.stages))
    else:
        print(f"{'checked' if check_only else 'wrote ' + output}: {scene.analysis.type} analysis")
    for b in bodies:
        print(f"  body {b.name}: {len(b.cells)} {b.cell_type} cells, {len(b.coords)} vertices")
    for sid, (name, count) in enumerate(face_counts.items(), start=1):
        print(f"  surface {sid} {name}: {count} faces")
    for c in scene.couples:
        out = f", {len(exclude[scene.couples.index(c)])} master nodes out of contact" if c.exclude else ""
        print(f"  couple k={c.k}: master {','.join(c.master)}, slave {','.join(c.slave)}, mu={c.mu:g}{out}")


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


# ---------------------------------------------------------------- writing

def _write(output, scene, bodies, labels, face_counts, exclude):
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
            write_metadata(partial, scene, bodies, face_counts, labels, exclude)
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
        arrays[f"coords{i}"] = body.coords
        arrays[f"faces{i}"] = body.boundary_faces[labelled].astype(np.int32)
        arrays[f"labels{i}"] = values[labelled]
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


def write_metadata(path, scene, bodies, face_counts, labels=None, exclude=None):
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
               newmark_beta=a.newmark_beta, newmark_gamma=a.newmark_gamma, mass=a.mass,
               **(dict(modes=a.modes, tie=int(a.tie)) if a.type == "modal" else {}))
        _list(root, "surfaces", face_counts.items(), lambda g, item: _attrs(
            g, name=item[0], id=surface_ids[item[0]], num_faces=item[1]))
        _list(root, "bodies", zip(scene.bodies, bodies), lambda g, item: _attrs(
            g, name=item[0].name, cell_type=item[1].cell_type, num_cells=len(item[1].cells),
            num_vertices=len(item[1].coords), **item[0].material,
            **({"element": item[0].element} if item[0].element else {}),
            **({"massless": 1} if item[0].massless else {})))
        def side_faces(c, column):  # faces of each body on one side of couple c: the edge weights of the decomposition
            if labels is None:
                return np.zeros(len(bodies), dtype=np.int32)
            return np.array([np.count_nonzero(lab[:, column] == c.k) for lab in labels], dtype=np.int32)

        def couple(g, item):
            i, c = item
            _attrs(g, k=c.k, mu=c.mu, master=",".join(c.master), slave=",".join(c.slave),
                   master_faces=side_faces(c, 1), slave_faces=side_faces(c, 2))
            if exclude is not None and len(exclude[i]):  # (body, vertex) of the master nodes out of contact
                g.create_dataset("exclude", data=exclude[i].astype(np.int32))

        _list(root, "couples", enumerate(scene.couples), couple)

        dirichlet = []
        for d in scene.dirichlet:
            index = time_function(d.time)
            dirichlet += [dict(surface=d.surface, surface_id=surface_ids[d.surface], component=comp,
                               value=d.value, time=d.time.kind, time_function=index)
                          for comp in d.components]
        _list(root, "dirichlet", dirichlet, lambda g, d: _attrs(g, **d))
        _list(root, "loads", scene.loads, lambda g, load: _attrs(
            g, kind=load.kind, vector=load.vector, value=load.value, surface=load.surface,
            surface_id=surface_ids.get(load.surface, -1), bodies=",".join(load.bodies),
            time=load.time.kind, time_function=time_function(load.time), stage=load.stage,
            **(dict(level=load.level, unit_weight=load.unit_weight, axis=load.axis)
               if load.kind == "hydrostatic" else {}),
            **(dict(velocity_function=time_function(Time("table", load.velocity)),
                    displacement_function=time_function(Time("table", load.displacement)))
               if load.kind == "ground_acceleration" else {})))
        _list(root, "added_mass", scene.added_mass, lambda g, m: _attrs(
            g, model="westergaard", surface=m.surface, surface_id=surface_ids[m.surface], density=m.density,
            level=m.level, bottom=m.bottom, axis=m.axis))
        _list(root, "absorbing", scene.absorbing, lambda g, x: _attrs(
            g, surface=x.surface, surface_id=surface_ids[x.surface], input=x.input))
        _list(root, "stages", scene.stages, lambda g, st: _attrs(
            g, name=st.name, type=st.analysis.type, start_time=st.start_time, dt=st.analysis.dt,
            final_time=st.analysis.final_time, newmark_beta=st.analysis.newmark_beta,
            newmark_gamma=st.analysis.newmark_gamma, mass=st.analysis.mass))
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
