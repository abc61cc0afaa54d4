"""Read and validate the YAML scene description (format: docs/scene.md).

Every user error raises InputError whose message starts with the key path of the
offending entry, e.g. "bodies.block1.material.E: must be > 0, got -1".
"""
import math
import os
import re
import sys
from dataclasses import dataclass, field

import numpy as np
import yaml


class InputError(Exception):
    """A user error in the scene or its meshes; the message names the input."""


def warn(message):
    print(f"mbcontact-prep: warning: {message}", file=sys.stderr)


def note(message):
    """What the prep did to the input that the user should know (stderr, exit status 0)."""
    print(f"mbcontact-prep: note: {message}", file=sys.stderr)


# ---------------------------------------------------------------- YAML loading

class _StrictLoader(yaml.SafeLoader):
    """SafeLoader that rejects duplicate keys (PyYAML silently keeps the last)."""

    def construct_mapping(self, node, deep=False):
        result = super().construct_mapping(node, deep)  # rejects unhashable keys
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            if key in seen:
                raise InputError(f"line {key_node.start_mark.line + 1}: duplicate key {key!r}")
            seen.add(key)
        return result


def _yaml_position(err):
    mark = getattr(err, "problem_mark", None)
    return f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""


def load_yaml(path):
    try:
        with open(path, encoding="utf-8") as f:
            doc = yaml.load(f, Loader=_StrictLoader)
    except OSError as err:
        raise InputError(f"cannot read scene file: {err.strerror}") from None
    except UnicodeDecodeError:
        raise InputError("scene file is not UTF-8 text") from None
    except yaml.YAMLError as err:
        raise InputError(f"YAML syntax error{_yaml_position(err)}: "
                         f"{getattr(err, 'problem', None) or err}") from None
    if not isinstance(doc, dict):
        raise InputError("the scene must be a YAML mapping (key: value lines)")
    return doc


# ---------------------------------------------------------------- value checks

def _describe(value):
    return f"{type(value).__name__} {value!r}"


def mapping(value, where, allowed, required=()):
    """Check that value is a mapping with only `allowed` keys and all `required` ones."""
    if value is None and not required:
        return {}
    if not isinstance(value, dict):
        raise InputError(f"{where}: expected a mapping, got {_describe(value)}")
    for key in value:
        if key not in allowed:
            raise InputError(f"{_join(where, key)}: unknown key (allowed here: {', '.join(allowed)})")
    for key in required:
        if key not in value:
            raise InputError(f"{where}: missing required key '{key}'")
    return value


def named(value, where):
    """A mapping name -> entry (meshes, bodies, points), in file order."""
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise InputError(f"{where}: expected a mapping of names to entries, got {_describe(value)}")
    for key in value:
        if not isinstance(key, str):
            raise InputError(f"{where}: names must be strings, got {_describe(key)}")
    return value


def _join(where, key):
    return f"{where}.{key}" if where else str(key)


def real(value, where, gt=None, ge=None, lt=None):
    """A finite float; accepts ints and numeric strings such as "1e10"."""
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise InputError(f"{where}: expected a number, got {value!r}") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"{where}: expected a number, got {_describe(value)}")
    value = float(value)
    if not math.isfinite(value):
        raise InputError(f"{where}: must be a finite number, got {value}")
    if gt is not None and not value > gt:
        raise InputError(f"{where}: must be > {gt:g}, got {value:g}")
    if ge is not None and not value >= ge:
        raise InputError(f"{where}: must be >= {ge:g}, got {value:g}")
    if lt is not None and not value < lt:
        raise InputError(f"{where}: must be < {lt:g}, got {value:g}")
    return value


INT32_MAX = 2**31 - 1  # the scene file stores integers as int32; a larger one would wrap
NAME_MAX = 255  # the solver's buffer for a name or the title (MBC_NAME_LEN - 1)
MAX_STEPS = 10**7  # the solver refuses more steps (docs/scene.md)
MAX_MU = 1e3  # the solver refuses larger friction coefficients (MBC_MAX_MU)


def integer(value, where, ge=None, le=INT32_MAX):
    if isinstance(value, bool) or not isinstance(value, int):
        raise InputError(f"{where}: expected an integer, got {_describe(value)}")
    if ge is not None and value < ge:
        raise InputError(f"{where}: must be >= {ge}, got {value}")
    if le is not None and value > le:
        raise InputError(f"{where}: must be <= {le}, got {value}")
    return value


def boolean(value, where):
    if isinstance(value, bool) or value in (0, 1):
        return bool(value)
    raise InputError(f"{where}: expected true or false, got {_describe(value)}")


def vector3(value, where):
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise InputError(f"{where}: expected 3 numbers [x, y, z], got {value!r}")
    return np.array([real(v, f"{where}[{i}]") for i, v in enumerate(value)])


def string(value, where, choices=None, maxlen=NAME_MAX):
    if not isinstance(value, str) or not value:
        raise InputError(f"{where}: expected a non-empty string, got {_describe(value)}")
    if maxlen is not None and len(value) > maxlen:
        raise InputError(f"{where}: longer than {maxlen} characters ({len(value)})")
    if not value.isascii():
        raise InputError(f"{where}: must be ASCII, got {value!r}")
    if choices is not None and value not in choices:
        raise InputError(f"{where}: unknown value {value!r} (expected one of: {', '.join(choices)})")
    return value


def name_list(value, where):
    """A name or a list of names (at least one); no commas (they join lists in the file)."""
    names = [value] if isinstance(value, str) else value
    if not isinstance(names, list) or not names:
        raise InputError(f"{where}: expected a name or a non-empty list of names, got {value!r}")
    names = [string(n, f"{where}[{i}]") for i, n in enumerate(names)]
    for n in names:
        if "," in n:
            raise InputError(f"{where}: name {n!r} must not contain ','")
    return names


def entries(value, where):
    """A list of mappings (a missing section is an empty list)."""
    if value is None:
        return []
    if not isinstance(value, list):
        raise InputError(f"{where}: expected a list of entries (lines starting with '- '), "
                         f"got {_describe(value)}")
    return value


# ---------------------------------------------------------------- time functions

@dataclass
class Time:
    kind: str                 # "constant" | "sudden" | "table"
    table: np.ndarray = None  # (n, 2) for "table"


def time_spec(value, where, kinds, base_dir="."):
    """`constant`, `sudden`, {table: [[t, f], ...]} or {csv: FILE, shift: s}: a table either
    way (t strictly increasing); a CSV's path is relative to the scene's folder."""
    if value is None:
        return Time("constant")
    if isinstance(value, str):
        if value not in kinds:
            raise InputError(f"{where}: unknown time {value!r} (expected "
                             f"{' | '.join(kinds)} | {{table: [[t, factor], ...]}} | {{csv: FILE}})")
        return Time(value)
    if isinstance(value, dict) and "csv" in value:
        spec = mapping(value, where, ("csv", "shift"), required=("csv",))
        path = os.path.join(base_dir, string(spec["csv"], f"{where}.csv", maxlen=None))
        table = _csv_table(path, f"{where}.csv")
        table[:, 0] += real(spec.get("shift", 0.0), f"{where}.shift")
        return Time("table", table)
    spec = mapping(value, where, ("table",), required=("table",))
    rows = spec["table"]
    if not isinstance(rows, list) or not rows:
        raise InputError(f"{where}.table: expected a non-empty list of [t, factor] pairs")
    table = np.empty((len(rows), 2))
    for i, row in enumerate(rows):
        if not isinstance(row, list) or len(row) != 2:
            raise InputError(f"{where}.table[{i}]: expected a pair [t, factor], got {row!r}")
        table[i] = [real(row[0], f"{where}.table[{i}][0]"), real(row[1], f"{where}.table[{i}][1]")]
        if i and table[i, 0] <= table[i - 1, 0]:
            raise InputError(f"{where}.table[{i}]: t must be strictly increasing "
                             f"(t={table[i, 0]:g} follows t={table[i - 1, 0]:g})")
    return Time("table", table)


def _csv_table(path, where):
    """Rows `t, factor` of a CSV file (comma, semicolon or blank separated); lines starting
    with '#' and a first line that is not numeric (a header) are skipped."""
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except OSError as err:
        raise InputError(f"{where}: cannot read {path}: {err.strerror}") from None
    except UnicodeDecodeError:
        raise InputError(f"{where}: {path} is not a UTF-8 text file") from None
    rows, header_seen = [], False
    for number, line in enumerate(lines, start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        fields = re.split(r"[,;\s]+", text.strip(",; "))
        try:
            values = [float(v) for v in fields]
        except ValueError:
            if not rows and not header_seen:
                header_seen = True
                continue
            raise InputError(f"{where}: {path} line {number}: expected two numbers 't, factor', "
                             f"got {line.strip()!r}") from None
        if len(values) != 2:
            raise InputError(f"{where}: {path} line {number}: expected two columns 't, factor', "
                             f"got {len(values)}")
        if not all(math.isfinite(v) for v in values):
            raise InputError(f"{where}: {path} line {number}: values must be finite, got {line.strip()!r}")
        if rows and values[0] <= rows[-1][0]:
            raise InputError(f"{where}: {path} line {number}: t must be strictly increasing "
                             f"(t={values[0]:g} follows t={rows[-1][0]:g})")
        rows.append(values)
    if not rows:
        raise InputError(f"{where}: {path} holds no 't, factor' rows")
    return np.array(rows, dtype=float)


# ---------------------------------------------------------------- scene entries

MATERIAL_DEFAULTS = dict(nu=0.0, density=0.0, damping=0.0, rayleigh_alpha=0.0, rayleigh_beta=0.0)
COMPONENTS = {"x": 0, "y": 1, "z": 2}
LOAD_KINDS = ("gravity", "body_force", "pressure", "traction", "hydrostatic", "ground_acceleration",
              "nodal_force", "line_force")
RIGID_COMPONENTS = {"x": 0, "y": 1, "z": 2, "rx": 3, "ry": 4, "rz": 5}
SCHEMES = ("newmark", "hht", "generalized_alpha")
FIELDS = ("displacement", "stress", "envelope")
DEFAULT_FIELDS = ("displacement", "stress")
ABSORBING_INPUTS = ("none", "outcrop", "incident")
ELEMENTS = ("hex8", "hex8i", "hex8b")  # the element of a hex body (a tet4 body has tet4)
IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


@dataclass
class Body:
    name: str
    mesh: str
    regions: list
    material: dict
    element: str = ""  # hex bodies: "hex8" | "hex8i" | "hex8b"; "" = the solver's default
    massless: bool = False  # no inertia in a dynamic analysis (a massless foundation)
    rigid: dict = None      # a rigid body: {reference, mass, inertia} (None: from its mesh); None: deformable


@dataclass
class Couple:
    k: int
    master: list
    slave: list
    mu: float
    exclude: list = field(default_factory=list)  # regions whose nodes carry no contact point
    sliding: str = ""     # "small" (pairs fixed per stage) or "finite"; "": -mbc_contact_sliding's default
    uplift: dict = None   # the water pressure on its faces (_uplift), None: none
    cohesion: float = 0.0          # joint law (docs/dam.md): 0 = unbonded Coulomb contact
    tensile_strength: float = 0.0  # resolved: cohesion / mu when not given
    mu_residual: float = 0.0       # resolved: mu when not given
    softening: float = 0.0         # softening_displacement: 0 = brittle


@dataclass
class Dirichlet:
    surface: str          # one of surface, nodes, body
    components: list      # 0, 1, 2 = x, y, z; a rigid body's 3, 4, 5 = rx, ry, rz
    value: float
    time: Time
    nodes: list = field(default_factory=list)  # node sets, node groups or regions: their nodes
    body: str = ""        # a whole body: its nodes, or a rigid body's motion


@dataclass
class Load:
    kind: str
    vector: np.ndarray
    value: float
    surface: str
    bodies: list
    time: Time
    level: float = 0.0        # hydrostatic: free surface coordinate along axis
    unit_weight: float = 0.0  # hydrostatic: pressure per depth (rho_w g)
    axis: int = 2             # hydrostatic: 0, 1, 2 = x, y, z (up)
    stage: int = 0            # the stage from which the load acts (stages[i].loads)
    where: str = ""           # its key path in the YAML (stages[i].loads[j]; "" for loads[i])
    velocity: np.ndarray = None      # ground_acceleration: the record's velocity and displacement
    displacement: np.ndarray = None  # tables (n, 2), integrated exactly from the acceleration's
    nodes: list = field(default_factory=list)  # nodal_force: the node sets it acts on (per node)
    line: list = field(default_factory=list)   # line_force: the line regions it acts on (per length)
    couple: int = -1          # uplift (made from a couple's `uplift`): the couple's index, its side 0 master / 1 slave
    side: int = 0


@dataclass
class NodeSet:
    kind: str             # plane | sphere | box | union | difference | intersection
    names: list = field(default_factory=list)  # union, difference (the first minus the others), intersection
    point: np.ndarray = None   # plane: a point of it; sphere: the centre
    normal: np.ndarray = None  # plane
    radius: float = 0.0        # sphere
    lo: np.ndarray = None      # box
    hi: np.ndarray = None
    tolerance: float = None    # None: 1e-6 of the bodies' extent
    bodies: list = field(default_factory=list)  # restricted to these bodies ([]: all)


@dataclass
class Initial:
    body: str             # one of body, nodes
    nodes: list
    displacement: object  # None, a 3-vector, or ("field", name)
    velocity: object


@dataclass
class Spring:
    nodes: list
    to: list              # [] : to the ground
    stiffness: np.ndarray
    damping: np.ndarray


@dataclass
class AddedMass:
    surface: str
    density: float   # of the water, in the scene's units
    level: float     # the reservoir's free surface along axis
    bottom: float    # the reservoir's floor along axis (None: the surface's lowest point, set by the prep)
    axis: int = 2


@dataclass
class Absorbing:
    surface: str
    input: str = "none"  # none | outcrop | incident: where the ground motion enters as 2 rho c v_incident


@dataclass
class Analysis:
    type: str = "static"
    dt: float = 1.0
    final_time: float = 1.0
    newmark_beta: float = 0.25
    newmark_gamma: float = 0.5
    mass: str = "consistent"
    scheme: str = "newmark"  # newmark | hht | generalized_alpha
    alpha: float = -0.3      # hht (Hilber-Hughes-Taylor, Code_Aster's sign): in [-1/3, 0]
    rho_inf: float = 0.8     # generalized_alpha (Chung-Hulbert): spectral radius at infinite frequency, in [0, 1]
    alpha_m: float = 0.0     # the generalized-alpha weights the solver uses (0, 0: Newmark)
    alpha_f: float = 0.0
    modes: int = 6        # modal: how many of the lowest modes
    tie: bool = True      # modal: the couples tied (bonded) or the bodies alone


@dataclass
class Stage:
    name: str
    analysis: Analysis
    start_time: float  # the end of the stage before (0 for the first): time runs on


@dataclass
class Point:
    name: str
    x: np.ndarray
    body: str


@dataclass
class Output:
    every: int = 1
    fields: list = field(default_factory=lambda: list(DEFAULT_FIELDS))
    energy: bool = False
    points: list = field(default_factory=list)


@dataclass
class Scene:
    title: str
    meshes: dict      # mesh name -> file path
    bodies: list
    couples: list
    dirichlet: list
    loads: list
    analysis: Analysis
    output: Output
    surfaces: dict    # surface name -> list of places it is referenced, in id order
    stages: list = field(default_factory=list)  # empty: one analysis (`analysis`)
    added_mass: list = field(default_factory=list)
    absorbing: list = field(default_factory=list)
    node_sets: dict = field(default_factory=dict)  # name -> NodeSet, in file order
    initial: list = field(default_factory=list)
    springs: list = field(default_factory=list)
    extrude: dict = field(default_factory=dict)  # mesh name -> (length, layers, linear): a 2D mesh extruded along z


TOP_KEYS = ("title", "meshes", "bodies", "node_sets", "couples", "dirichlet", "loads", "initial", "springs",
            "added_mass", "absorbing",
            "analysis", "stages", "output")


def parse_scene(doc, base_dir):
    """Validate the YAML document and return a Scene (mesh paths made absolute)."""
    mapping(doc, "", TOP_KEYS, required=("meshes", "bodies"))
    title = doc.get("title")
    title = "" if title in (None, "") else string(str(title), "title")
    extrude = {}
    meshes = _meshes(doc["meshes"], base_dir, extrude)
    bodies = _bodies(doc["bodies"], meshes)
    body_names = [b.name for b in bodies]
    couples = _couples(doc.get("couples"), base_dir)
    node_sets = _node_sets(doc.get("node_sets"), body_names)
    dirichlet = [_dirichlet(e, f"dirichlet[{i}]", base_dir, bodies) for i, e in enumerate(entries(doc.get("dirichlet"), "dirichlet"))]
    initial = [_initial(e, f"initial[{i}]", body_names) for i, e in enumerate(entries(doc.get("initial"), "initial"))]
    springs = [_spring(e, f"springs[{i}]") for i, e in enumerate(entries(doc.get("springs"), "springs"))]
    loads = [load for i, e in enumerate(entries(doc.get("loads"), "loads"))
             for load in _loads(e, f"loads[{i}]", body_names, base_dir)]
    added_mass = [_added_mass(e, f"added_mass[{i}]") for i, e in enumerate(entries(doc.get("added_mass"), "added_mass"))]
    absorbing = [_absorbing(e, f"absorbing[{i}]") for i, e in enumerate(entries(doc.get("absorbing"), "absorbing"))]
    if "stages" in doc and "analysis" in doc:
        raise InputError("analysis: a scene with stages gives each stage its analysis "
                         "(stages[i].analysis), not a top-level one")
    stages = _stages(doc.get("stages"), loads, body_names, base_dir) if "stages" in doc else []
    analysis = stages[0].analysis if stages else _analysis(doc.get("analysis"))
    output = _output(doc.get("output"), body_names)
    for where, a in ([(f"stages[{i}]", st.analysis) for i, st in enumerate(stages)] or [("analysis", analysis)]):
        if a.type not in ("dynamic", "modal"):
            continue
        for b in bodies:
            if b.material["density"] == 0 and not b.massless and b.rigid is None:
                raise InputError(f"bodies.{b.name}.material.density: a {a.type} analysis ({where}) needs "
                                 f"density > 0 for every body (body '{b.name}' has 0; `massless: true` "
                                 "makes a body without inertia)")
    dynamic = any(a.type == "dynamic" for a in ([st.analysis for st in stages] or [analysis]))
    for load in loads:
        if load.kind == "ground_acceleration" and not dynamic:
            raise InputError(f"{load.where}: a ground acceleration needs a dynamic analysis (or a dynamic stage)")
    if absorbing and not dynamic:
        raise InputError("absorbing: dashpots act in a dynamic analysis (or a dynamic stage) only")
    if added_mass and not dynamic and analysis.type != "modal":
        raise InputError("added_mass[0]: an added mass acts in a dynamic or modal analysis only")
    if any(x.input != "none" for x in absorbing) and not any(l.kind == "ground_acceleration" for l in loads):
        raise InputError("absorbing: an input surface (input: outcrop or incident) needs a ground_acceleration "
                         "load (the record that enters through it)")
    surfaces = _surface_references(doc, couples, dirichlet, loads, added_mass, absorbing)
    loads += _uplift_loads(couples, loads)
    if initial and not dynamic:
        raise InputError("initial: initial conditions start a dynamic analysis (or a first dynamic stage)")
    if initial and stages and stages[0].analysis.type != "dynamic":
        raise InputError("initial: initial conditions need the first stage to be dynamic (a static stage starts "
                         "from rest and from its own equilibrium)")
    return Scene(title, meshes, bodies, couples, dirichlet, loads, analysis, output, surfaces, stages,
                 added_mass, absorbing, node_sets, initial, springs, extrude)


def _meshes(value, base_dir, extrude=None):
    """name -> file, or name -> {file: FILE, extrude: {length: L, layers: n, linear: b}} (a 2D mesh made 3D by
    extruding it along z, as a plane-strain model of another code); extrude collects the latter."""
    meshes = named(value, "meshes")
    if not meshes:
        raise InputError("meshes: at least one mesh is needed (name: file)")
    out = {}
    for name, spec in meshes.items():
        where = f"meshes.{name}"
        if isinstance(spec, dict):
            spec = mapping(spec, where, ("file", "extrude"), required=("file",))
            if "extrude" in spec:
                ex = mapping(spec["extrude"], f"{where}.extrude", ("length", "layers", "linear"), required=("length",))
                length = real(ex["length"], f"{where}.extrude.length", gt=0)
                layers = integer(ex.get("layers", 1), f"{where}.extrude.layers", ge=1, le=10000)
                linear = boolean(ex.get("linear", False), f"{where}.extrude.linear")
                if extrude is not None:
                    extrude[name] = (length, layers, linear)
            spec = spec["file"]
        out[name] = os.path.join(base_dir, string(spec, where, maxlen=None))
    return out


def _bodies(value, meshes):
    bodies = named(value, "bodies")
    if not bodies:
        raise InputError("bodies: at least one body is needed")
    return [_body(name, spec, meshes) for name, spec in bodies.items()]


def _body(name, spec, meshes):
    where = f"bodies.{name}"
    if not IDENTIFIER.match(name):
        raise InputError(f"{where}: body names must be identifiers ([A-Za-z_][A-Za-z0-9_]*), "
                         f"got {name!r}")
    spec = mapping(spec, where, ("mesh", "regions", "material", "element", "massless", "rigid"), required=("mesh", "regions"))
    rigid = _rigid(spec.get("rigid", False), f"{where}.rigid")
    if "material" not in spec and rigid is None:
        raise InputError(f"{where}: missing required key 'material'")
    mesh = string(spec["mesh"], f"{where}.mesh")
    if mesh not in meshes:
        raise InputError(f"{where}.mesh: unknown mesh {mesh!r} (meshes: {', '.join(meshes)})")
    regions = name_list(spec["regions"], f"{where}.regions")
    element = string(spec["element"], f"{where}.element", choices=ELEMENTS) if "element" in spec else ""
    massless = boolean(spec.get("massless", False), f"{where}.massless")
    if rigid is not None and (element or massless):
        raise InputError(f"{where}.{'element' if element else 'massless'}: not for a rigid body")
    material = _material(spec.get("material", {}), f"{where}.material", rigid=rigid is not None)
    return Body(name, mesh, regions, material, element, massless, rigid)


def _rigid(value, where):
    """`rigid: true` or {reference: [x, y, z], mass: m, inertia: [[...], [...], [...]]}: a body of six
    DOFs (the reference point's translation and the rotation about it); what is not given comes
    from its mesh and density. None for a deformable body."""
    if value is False or value is None:
        return None
    if value is True:
        return {}
    spec = mapping(value, where, ("reference", "mass", "inertia"))
    out = {}
    if "reference" in spec:
        out["reference"] = vector3(spec["reference"], f"{where}.reference")
    if "mass" in spec:
        out["mass"] = real(spec["mass"], f"{where}.mass", gt=0)
    if "inertia" in spec:
        rows = spec["inertia"]
        if not isinstance(rows, list) or len(rows) != 3:
            raise InputError(f"{where}.inertia: expected a 3 x 3 matrix [[Ixx, Ixy, Ixz], [...], [...]] about the reference point")
        inertia = np.array([vector3(r, f"{where}.inertia[{i}]") for i, r in enumerate(rows)])
        if not np.allclose(inertia, inertia.T, rtol=1e-12, atol=0) or np.any(np.linalg.eigvalsh(inertia) <= 0):
            raise InputError(f"{where}.inertia: must be symmetric and positive definite, got {inertia.tolist()}")
        out["inertia"] = inertia
        if "mass" not in spec:
            raise InputError(f"{where}.inertia: give the mass with it (an inertia about the reference point, taken as "
                             "the mass centre); without both, the mass and inertia come from the cells and the density")
    return out


MATERIAL_RANGE = (1e-100, 1e100)  # the solver's MBC_MATERIAL_MIN/MAX: squares stay normal doubles


def _material(value, where, rigid=False):
    """A rigid body needs no E (1 is written: unused) and takes density alone."""
    spec = mapping(value, where, ("E",) + tuple(MATERIAL_DEFAULTS), required=() if rigid else ("E",))
    if rigid:
        for key in spec:
            if key not in ("density",):
                raise InputError(f"{where}.{key}: a rigid body's material has a density only")
    material = dict(E=real(spec.get("E", 1.0), f"{where}.E", gt=0))
    for key, default in MATERIAL_DEFAULTS.items():
        bounds = dict(gt=-1, lt=0.5) if key == "nu" else dict(ge=0)
        material[key] = real(spec.get(key, default), f"{where}.{key}", **bounds)
    lo, hi = MATERIAL_RANGE
    for key, v in material.items():
        if key != "nu" and v != 0 and not lo <= v <= hi:
            raise InputError(f"{where}.{key}: {v:g} lies outside [{lo:g}, {hi:g}]: no material in any unit "
                             f"system, and the stiffness, mass and energies made from it leave double precision")
    return material


def _couples(value, base_dir="."):
    couples, seen = [], {}
    for i, spec in enumerate(entries(value, "couples")):
        where = f"couples[{i}]"
        spec = mapping(spec, where, ("k", "master", "slave", "mu", "exclude", "sliding", "uplift", "cohesion", "tensile_strength",
                                        "mu_residual", "softening_displacement"), required=("master", "slave"))
        k = integer(spec.get("k", i + 1), f"{where}.k", ge=1)
        if k in seen:
            raise InputError(f"{where}.k: couple k={k} is already defined by couples[{seen[k]}]")
        seen[k] = i
        couples.append(Couple(k, name_list(spec["master"], f"{where}.master (couple k={k})"),
                              name_list(spec["slave"], f"{where}.slave (couple k={k})"),
                              real(spec.get("mu", 0.0), f"{where}.mu", ge=0),
                              name_list(spec["exclude"], f"{where}.exclude (couple k={k})") if "exclude" in spec else [],
                              string(spec["sliding"], f"{where}.sliding", ("finite", "small")) if "sliding" in spec else ""))
        if "uplift" in spec:
            couples[-1].uplift = _uplift(spec["uplift"], f"{where}.uplift", k, base_dir)
        if couples[-1].mu > MAX_MU:
            raise InputError(f"{where}.mu: {couples[-1].mu:g} is not a friction coefficient (at most "
                             f"{MAX_MU:g}, a friction angle of 89.94 degrees)")
        _joint_law(couples[-1], spec, where)
    return couples


def _joint_law(c, spec, where):
    """The bonded joint's keys (docs/dam.md): cohesion c, tensile strength f_t <= c / mu (the apex of
    the Mohr-Coulomb cone), residual friction after the bond breaks."""
    for key in ("tensile_strength", "mu_residual", "softening_displacement"):
        if key in spec and "cohesion" not in spec:
            raise InputError(f"{where}.{key} (couple k={c.k}): a joint law's key needs cohesion (> 0) on the couple")
    c.cohesion = real(spec.get("cohesion", 0.0), f"{where}.cohesion (couple k={c.k})", ge=0)
    c.mu_residual = real(spec.get("mu_residual", c.mu), f"{where}.mu_residual (couple k={c.k})", ge=0)
    if c.cohesion == 0:
        if "tensile_strength" in spec or "mu_residual" in spec or "softening_displacement" in spec:
            raise InputError(f"{where} (couple k={c.k}): tensile_strength, mu_residual and softening_displacement belong "
                             f"to a bonded joint: give cohesion > 0, or leave them out")
        c.tensile_strength, c.mu_residual = 0.0, c.mu
        return
    if c.mu == 0:
        raise InputError(f"{where}.cohesion (couple k={c.k}): a bonded joint needs friction mu > 0 (its cone "
                         f"|t| <= c + mu p has its apex at p = -c/mu; with mu = 0 the tensile strength is unbounded)")
    apex = c.cohesion / c.mu
    c.tensile_strength = real(spec.get("tensile_strength", apex), f"{where}.tensile_strength (couple k={c.k})", ge=0)
    if c.tensile_strength > apex * (1 + 1e-12):
        raise InputError(f"{where}.tensile_strength (couple k={c.k}): {c.tensile_strength:g} exceeds cohesion / mu = "
                         f"{c.cohesion:g} / {c.mu:g} = {apex:g}, the apex of the Mohr-Coulomb cone")
    c.tensile_strength = min(c.tensile_strength, apex)
    c.softening = real(spec.get("softening_displacement", 0.0), f"{where}.softening_displacement (couple k={c.k})", ge=0)
    if c.mu_residual > MAX_MU:
        raise InputError(f"{where}.mu_residual (couple k={c.k}): {c.mu_residual:g} is not a friction coefficient "
                         f"(at most {MAX_MU:g})")


UPLIFT_KEYS = ("origin", "direction", "length", "unit_weight", "heel_head", "tail_head", "drain",
               "drain_efficiency", "table", "penetration", "level", "axis", "threshold", "time")


def _uplift(value, where, k, base_dir="."):
    """A couple's `uplift`: the heel-to-toe law with an optional drain line, or a table; optionally
    the reservoir's water entering the joint where it opens (docs/scene.md, Couples). Keys that
    default to the scene's hydrostatic load (level, unit_weight, axis, heel_head) are settled by
    _uplift_loads once the loads are read."""
    at = f"{where} (couple k={k})"
    spec = mapping(value, at, UPLIFT_KEYS, required=("origin", "direction", "length"))
    u = dict(where=at)
    u["origin"] = vector3(spec["origin"], f"{at}.origin")
    d = vector3(spec["direction"], f"{at}.direction")
    if not np.linalg.norm(d) > 0:
        raise InputError(f"{at}.direction: must not be zero (the direction from the heel to the toe)")
    u["direction"] = d / np.linalg.norm(d)
    u["length"] = real(spec["length"], f"{at}.length", gt=0)
    if "table" in spec:
        for key in ("heel_head", "tail_head", "drain", "drain_efficiency"):
            if key in spec:
                raise InputError(f"{at}.{key}: a table gives the pressure by itself; {key} belongs to the "
                                 "heel-to-toe law (give one or the other)")
        rows = spec["table"]
        if not isinstance(rows, list) or len(rows) < 2:
            raise InputError(f"{at}.table: expected at least two [position, pressure] pairs")
        table = np.empty((len(rows), 2))
        for i, row in enumerate(rows):
            if not isinstance(row, list) or len(row) != 2:
                raise InputError(f"{at}.table[{i}]: expected a pair [position, pressure], got {row!r}")
            table[i] = [real(row[0], f"{at}.table[{i}][0]"), real(row[1], f"{at}.table[{i}][1]", ge=0)]
            if i and table[i, 0] <= table[i - 1, 0]:
                raise InputError(f"{at}.table[{i}]: positions must be strictly increasing "
                                 f"({table[i, 0]:g} follows {table[i - 1, 0]:g})")
        u["table"] = table
    else:
        u["table"] = None
        if "heel_head" in spec:
            u["heel_head"] = real(spec["heel_head"], f"{at}.heel_head", ge=0)
        u["tail_head"] = real(spec.get("tail_head", 0.0), f"{at}.tail_head", ge=0)
        if "heel_head" in u and u["tail_head"] > u["heel_head"]:
            raise InputError(f"{at}.tail_head: {u['tail_head']:g} is above heel_head {u['heel_head']:g} "
                             "(the law runs from the reservoir's head down to the tail water's)")
        u["drain"] = -1.0
        u["drain_efficiency"] = 0.0
        if "drain" in spec:
            if isinstance(spec["drain"], dict):  # a plane: where it crosses the line from the heel along direction
                plane = mapping(spec["drain"], f"{at}.drain", ("point", "normal"), required=("point", "normal"))
                point, normal = vector3(plane["point"], f"{at}.drain.point"), vector3(plane["normal"], f"{at}.drain.normal")
                if not abs(normal @ u["direction"]) > 1e-6 * np.linalg.norm(normal):
                    raise InputError(f"{at}.drain.normal: the drain plane must cross the joint's direction "
                                     f"{list(u['direction'])} (its normal is perpendicular to it)")
                u["drain"] = float((point - u["origin"]) @ normal / (normal @ u["direction"]))
                if not u["drain"] > 0:
                    raise InputError(f"{at}.drain: the drain plane crosses the joint at {u['drain']:g} from the heel, "
                                     "not downstream of it")
            else:
                u["drain"] = real(spec["drain"], f"{at}.drain", gt=0)
            if not u["drain"] < u["length"]:
                raise InputError(f"{at}.drain: the drain line at {u['drain']:g} from the heel must lie within "
                                 f"the joint (0 < drain < length = {u['length']:g})")
            if "drain_efficiency" not in spec:
                raise InputError(f"{at}.drain_efficiency: required with a drain line (USACE and FERC "
                                 "credit at most 0.5 without measurements)")
            u["drain_efficiency"] = real(spec["drain_efficiency"], f"{at}.drain_efficiency", ge=0)
            if u["drain_efficiency"] > 1:
                raise InputError(f"{at}.drain_efficiency: must be in [0, 1], got {u['drain_efficiency']:g}")
        elif "drain_efficiency" in spec:
            raise InputError(f"{at}.drain_efficiency: given without a drain line (key drain)")
    if "unit_weight" in spec:
        u["unit_weight"] = real(spec["unit_weight"], f"{at}.unit_weight", ge=0)
    if "level" in spec:
        u["level"] = real(spec["level"], f"{at}.level")
    axis = spec.get("axis", None)
    if axis is not None and (not isinstance(axis, str) or axis not in COMPONENTS):
        raise InputError(f"{at}.axis: expected x, y or z (the upward axis), got {axis!r}")
    if axis is not None:
        u["axis"] = COMPONENTS[axis]
    u["penetration"] = boolean(spec.get("penetration", False), f"{at}.penetration")
    u["threshold"] = real(spec.get("threshold", 0.0), f"{at}.threshold")
    u["time"] = time_spec(spec.get("time"), f"{at}.time", ("constant", "sudden"), base_dir)
    return u


def _uplift_loads(couples, loads):
    """Settles the couples' uplift keys left to the hydrostatic load (the reservoir's level, unit
    weight and upward axis, when the scene has one such load or several that agree; the heel's
    head = level - the heel's height) and returns the uplift loads: one per surface of each side."""
    hyd = [l for l in loads if l.kind == "hydrostatic"]
    out = []
    for i, c in enumerate(couples):
        u = c.uplift
        if u is None:
            continue
        at = u["where"]
        for key, attr in (("level", "level"), ("unit_weight", "unit_weight"), ("axis", "axis")):
            if key in u:
                continue
            values = sorted({getattr(l, attr) for l in hyd})
            needed = (u["table"] is None or u["penetration"]) if key == "unit_weight" else \
                u["penetration"] or (key == "level" and u["table"] is None and "heel_head" not in u)
            if len(values) == 1:
                u[key] = values[0]
            elif key == "axis":
                u[key] = 2
            elif needed:
                why = "no hydrostatic load" if not values else f"hydrostatic loads at several {key}s ({', '.join(f'{v:g}' for v in values)})"
                raise InputError(f"{at}.{key}: required (the scene has {why} to take it from)")
            else:
                u[key] = 0.0
        if u["table"] is None and "heel_head" not in u:
            u["heel_head"] = max(u["level"] - u["origin"][u["axis"]], 0.0)
            if u["tail_head"] > u["heel_head"]:
                raise InputError(f"{at}.tail_head: {u['tail_head']:g} is above the heel's head {u['heel_head']:g} "
                                 f"(level {u['level']:g} minus the heel's height {u['origin'][u['axis']]:g})")
        for side, names in enumerate((c.master, c.slave)):
            for name in names:
                out.append(Load("uplift", np.zeros(3), 0.0, name, [], u["time"], couple=i, side=side,
                                where=f"{at} on surface {name}"))
    return out


def _dirichlet(spec, where, base_dir=".", bodies=()):
    """On a surface (its faces' nodes), on nodes (node sets, node groups, the nodes of regions of any
    dimension) or on a body (all its nodes; a rigid body's motion: x, y, z, rx, ry, rz)."""
    spec = mapping(spec, where, ("surface", "nodes", "body", "components", "value", "time"))
    given = [k for k in ("surface", "nodes", "body") if k in spec]
    if len(given) != 1:
        raise InputError(f"{where}: give one of surface, nodes or body (got {', '.join(given) or 'none'})")
    rigid = False
    if "body" in spec:
        body = string(spec["body"], f"{where}.body")
        known = {b.name: b for b in bodies}
        if body not in known:
            raise InputError(f"{where}.body: unknown body {body!r} (bodies: {', '.join(known)})")
        rigid = known[body].rigid is not None
    d = Dirichlet(string(spec["surface"], f"{where}.surface") if "surface" in spec else "",
                  _components(spec.get("components", "all"), f"{where}.components", rigid),
                  real(spec.get("value", 0.0), f"{where}.value"),
                  time_spec(spec.get("time"), f"{where}.time", ("constant",), base_dir))
    if "nodes" in spec:
        d.nodes = name_list(spec["nodes"], f"{where}.nodes")
    if "body" in spec:
        d.body = spec["body"]
    return d


def _components(value, where, rigid=False):
    names = RIGID_COMPONENTS if rigid else COMPONENTS
    if value == "all":
        return list(names.values())
    listed = [value] if isinstance(value, str) else value
    if not isinstance(listed, list) or not listed:
        raise InputError(f"{where}: expected 'all' or a list of {', '.join(names)}, got {value!r}")
    components = []
    for n in listed:
        if not isinstance(n, str) or n not in names:
            raise InputError(f"{where}: unknown component {n!r} (expected {', '.join(names)} or all"
                             + ("" if rigid else "; rx, ry, rz only for a rigid body") + ")")
        if names[n] in components:
            raise InputError(f"{where}: component {n!r} listed twice")
        components.append(names[n])
    return components


_LOAD_KEYS = {  # kind -> (required keys, optional keys) besides kind and time
    "gravity": (("vector",), ("bodies",)),
    "body_force": (("vector",), ("bodies",)),
    "pressure": (("surface", "value"), ()),
    "traction": (("surface", "vector"), ()),
    "hydrostatic": (("surface", "level", "unit_weight"), ("axis",)),
    "nodal_force": (("nodes", "vector"), ()),
    "line_force": (("line", "vector"), ()),
}


def _loads(spec, where, body_names, base_dir="."):
    """The scene loads of one YAML entry: one, or one per component of a ground acceleration."""
    if isinstance(spec, dict) and spec.get("kind") == "ground_acceleration":
        return _ground_acceleration(spec, where, body_names, base_dir)
    load = _load(spec, where, body_names, base_dir)
    load.where = where
    return [load]


def _record_component(value, where, base_dir):
    """One component of a ground acceleration: (t, a) in the scene's units, before the entry's
    scale, shift and baseline."""
    from .records import G_STANDARD, RecordError, read_at2, read_table

    spec = mapping(value, where, ("at2", "csv", "table", "column", "dt", "scale", "g"))
    sources = [k for k in ("at2", "csv", "table") if k in spec]
    if len(sources) != 1:
        raise InputError(f"{where}: give the record as one of at2: FILE (PEER NGA), csv: FILE (a table) "
                         f"or table: [[t, a], ...], got {', '.join(sources) or 'none'}")
    scale = real(spec.get("scale", 1.0), f"{where}.scale")
    try:
        if "at2" in spec:
            for key in ("column", "dt"):
                if key in spec:
                    raise InputError(f"{where}.{key}: not for an .AT2 file (its header gives NPTS and DT)")
            g = real(spec.get("g", G_STANDARD), f"{where}.g", gt=0)
            dt, a = read_at2(os.path.join(base_dir, string(spec["at2"], f"{where}.at2", maxlen=None)))
            return dt * np.arange(len(a)), a * g * scale
        if "g" in spec:
            raise InputError(f"{where}.g: only for an .AT2 record (in g); scale a table with scale")
        if "csv" in spec:
            column = integer(spec["column"], f"{where}.column", ge=1) if "column" in spec else None
            dt = real(spec["dt"], f"{where}.dt", gt=0) if "dt" in spec else None
            t, a = read_table(os.path.join(base_dir, string(spec["csv"], f"{where}.csv", maxlen=None)), column, dt)
            return t, a * scale
    except RecordError as err:
        raise InputError(f"{where}: {err}") from None
    for key in ("column", "dt"):
        if key in spec:
            raise InputError(f"{where}.{key}: only for a csv record")
    table = time_spec({"table": spec["table"]}, where, ()).table
    if len(table) < 2:
        raise InputError(f"{where}.table: a record needs at least 2 rows")
    return table[:, 0], table[:, 1] * scale


def _ground_acceleration(spec, where, body_names, base_dir):
    """kind ground_acceleration: x, y, z records (at least one) of the base's acceleration; each
    becomes a scene load along its axis with its acceleration, velocity and displacement tables."""
    from .records import BASELINES, baseline_correct, integrate, padded

    mapping(spec, where, ("kind", "x", "y", "z", "scale", "shift", "baseline", "bodies"))
    comps = [c for c in ("x", "y", "z") if c in spec]
    if not comps:
        raise InputError(f"{where}: a ground acceleration needs at least one of x, y, z (a record each)")
    scale = real(spec.get("scale", 1.0), f"{where}.scale")
    shift = real(spec.get("shift", 0.0), f"{where}.shift")
    baseline = string(spec.get("baseline", "none"), f"{where}.baseline", choices=tuple(BASELINES))
    bodies = name_list(spec["bodies"], f"{where}.bodies") if "bodies" in spec else []
    for b in bodies:
        if b not in body_names:
            raise InputError(f"{where}.bodies: unknown body {b!r} (bodies: {', '.join(body_names)})")
    loads = []
    for c in comps:
        t, a = _record_component(spec[c], f"{where}.{c}", base_dir)
        a = baseline_correct(t, a * scale, BASELINES[baseline])
        t, a = padded(t + shift, a)
        v, d = integrate(t, a)
        vector = np.zeros(3)
        vector[COMPONENTS[c]] = 1.0
        load = Load("ground_acceleration", vector, 0.0, "", bodies, Time("table", np.column_stack([t, a])))
        load.velocity, load.displacement = np.column_stack([t, v]), np.column_stack([t, d])
        load.where = f"{where}.{c}"
        loads.append(load)
    return loads


def _added_mass(spec, where):
    spec = mapping(spec, where, ("surface", "density", "level", "bottom", "axis", "model"),
                   required=("surface", "density", "level"))
    string(spec.get("model", "westergaard"), f"{where}.model", choices=("westergaard",))
    axis = spec.get("axis", "z")
    if not isinstance(axis, str) or axis not in COMPONENTS:
        raise InputError(f"{where}.axis: expected x, y or z (the upward axis), got {axis!r}")
    m = AddedMass(string(spec["surface"], f"{where}.surface"), real(spec["density"], f"{where}.density", gt=0),
                  real(spec["level"], f"{where}.level"),
                  real(spec["bottom"], f"{where}.bottom") if "bottom" in spec else None, COMPONENTS[axis])
    if m.bottom is not None and not m.bottom < m.level:
        raise InputError(f"{where}.bottom: the reservoir's floor {m.bottom:g} must lie below its level {m.level:g}")
    return m


def _absorbing(spec, where):
    spec = mapping(spec, where, ("surface", "input"), required=("surface",))
    return Absorbing(string(spec["surface"], f"{where}.surface"),
                     string(spec.get("input", "none"), f"{where}.input", choices=ABSORBING_INPUTS))


def _load(spec, where, body_names, base_dir="."):
    if not isinstance(spec, dict) or "kind" not in spec:
        raise InputError(f"{where}: expected a mapping with a 'kind' ({', '.join(LOAD_KINDS)})")
    kind = string(spec["kind"], f"{where}.kind", choices=LOAD_KINDS)
    required, optional = _LOAD_KEYS[kind]
    mapping(spec, where, ("kind", "time") + required + optional, required=required)
    bodies = name_list(spec["bodies"], f"{where}.bodies") if "bodies" in spec else []
    for b in bodies:
        if b not in body_names:
            raise InputError(f"{where}.bodies: unknown body {b!r} (bodies: {', '.join(body_names)})")
    load = Load(kind,
                vector3(spec["vector"], f"{where}.vector") if "vector" in spec else np.zeros(3),
                real(spec["value"], f"{where}.value") if "value" in spec else 0.0,
                string(spec["surface"], f"{where}.surface") if "surface" in spec else "",
                bodies,
                time_spec(spec.get("time"), f"{where}.time", ("constant", "sudden"), base_dir))
    if kind == "hydrostatic":
        load.level = real(spec["level"], f"{where}.level")
        load.unit_weight = real(spec["unit_weight"], f"{where}.unit_weight", ge=0)
        axis = spec.get("axis", "z")
        if not isinstance(axis, str) or axis not in COMPONENTS:
            raise InputError(f"{where}.axis: expected x, y or z (the upward axis), got {axis!r}")
        load.axis = COMPONENTS[axis]
    if kind == "nodal_force":
        load.nodes = name_list(spec["nodes"], f"{where}.nodes")
    if kind == "line_force":
        load.line = name_list(spec["line"], f"{where}.line")
    return load


def _node_sets(value, body_names):
    """node_sets: name -> a selection of the bodies' nodes, as Code_Aster's DEFI_GROUP/CREA_GROUP_NO:
    {plane: {point, normal}} (within `tolerance` of it), {sphere: {centre, radius}},
    {box: {lo, hi}}, {union | intersection | difference: [names]} (difference: the first minus the
    others); `bodies` restricts any of them."""
    sets = {}
    for name, spec in named(value, "node_sets").items():
        where = f"node_sets.{name}"
        string(name, where)
        if "," in name:
            raise InputError(f"{where}: a name must not contain ','")
        kinds = ("plane", "sphere", "box", "union", "difference", "intersection")
        spec = mapping(spec, where, kinds + ("tolerance", "bodies"))
        given = [k for k in kinds if k in spec]
        if len(given) != 1:
            raise InputError(f"{where}: give one of {', '.join(kinds)} (got {', '.join(given) or 'none'})")
        kind = given[0]
        ns = NodeSet(kind)
        if "tolerance" in spec:
            ns.tolerance = real(spec["tolerance"], f"{where}.tolerance", ge=0)
        if "bodies" in spec:
            ns.bodies = name_list(spec["bodies"], f"{where}.bodies")
            for b in ns.bodies:
                if b not in body_names:
                    raise InputError(f"{where}.bodies: unknown body {b!r} (bodies: {', '.join(body_names)})")
        sub = spec[kind]
        if kind == "plane":
            sub = mapping(sub, f"{where}.plane", ("point", "normal"), required=("point", "normal"))
            ns.point = vector3(sub["point"], f"{where}.plane.point")
            normal = vector3(sub["normal"], f"{where}.plane.normal")
            if not np.linalg.norm(normal) > 0:
                raise InputError(f"{where}.plane.normal: must not be zero")
            ns.normal = normal / np.linalg.norm(normal)
        elif kind == "sphere":
            sub = mapping(sub, f"{where}.sphere", ("centre", "radius"), required=("centre", "radius"))
            ns.point = vector3(sub["centre"], f"{where}.sphere.centre")
            ns.radius = real(sub["radius"], f"{where}.sphere.radius", ge=0)
        elif kind == "box":
            sub = mapping(sub, f"{where}.box", ("lo", "hi"), required=("lo", "hi"))
            ns.lo, ns.hi = vector3(sub["lo"], f"{where}.box.lo"), vector3(sub["hi"], f"{where}.box.hi")
            if np.any(ns.lo > ns.hi):
                raise InputError(f"{where}.box: lo {ns.lo.tolist()} must not exceed hi {ns.hi.tolist()}")
        else:
            ns.names = name_list(sub, f"{where}.{kind}")
            for n in ns.names:
                if n == name:
                    raise InputError(f"{where}.{kind}: a node set cannot use itself")
        sets[name] = ns
    return sets


def _nodal_value(value, where):
    """An initial displacement or velocity: [x, y, z] for every node, or {field: NAME} (a point
    field of the body's mesh file, 3 components per node)."""
    if isinstance(value, dict):
        spec = mapping(value, where, ("field",), required=("field",))
        return ("field", string(spec["field"], f"{where}.field", maxlen=None))
    return vector3(value, where)


def _initial(spec, where, body_names):
    spec = mapping(spec, where, ("body", "nodes", "displacement", "velocity"))
    given = [k for k in ("body", "nodes") if k in spec]
    if len(given) != 1:
        raise InputError(f"{where}: give one of body or nodes (got {', '.join(given) or 'none'})")
    if "displacement" not in spec and "velocity" not in spec:
        raise InputError(f"{where}: give a displacement, a velocity or both")
    body = string(spec["body"], f"{where}.body") if "body" in spec else ""
    if body and body not in body_names:
        raise InputError(f"{where}.body: unknown body {body!r} (bodies: {', '.join(body_names)})")
    return Initial(body, name_list(spec["nodes"], f"{where}.nodes") if "nodes" in spec else [],
                   _nodal_value(spec["displacement"], f"{where}.displacement") if "displacement" in spec else None,
                   _nodal_value(spec["velocity"], f"{where}.velocity") if "velocity" in spec else None)


def _spring(spec, where):
    """A discrete spring and dashpot at every node of `nodes`, to the ground or to the nearest node of
    `to`, with a stiffness and a damping along x, y, z (global axes) each."""
    spec = mapping(spec, where, ("nodes", "to", "stiffness", "damping"), required=("nodes",))
    k = np.array([real(v, f"{where}.stiffness[{i}]", ge=0) for i, v in enumerate(_triple(spec.get("stiffness", [0, 0, 0]), f"{where}.stiffness"))])
    c = np.array([real(v, f"{where}.damping[{i}]", ge=0) for i, v in enumerate(_triple(spec.get("damping", [0, 0, 0]), f"{where}.damping"))])
    if not (np.any(k > 0) or np.any(c > 0)):
        raise InputError(f"{where}: give a stiffness or a damping > 0 along some axis")
    for key, v in (("stiffness", k), ("damping", c)):
        for i, x in enumerate(v):
            if x != 0 and not 1e-100 <= x <= 1e100:
                raise InputError(f"{where}.{key}[{i}]: {x:g} lies outside [1e-100, 1e100]")
    return Spring(name_list(spec["nodes"], f"{where}.nodes"),
                  name_list(spec["to"], f"{where}.to") if "to" in spec else [], k, c)


def _triple(value, where):
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise InputError(f"{where}: expected 3 numbers [x, y, z], got {value!r}")
    return value


def _analysis(value, where="analysis", start=0.0):
    """The analysis settings; a stage's (`where` = stages[i].analysis) runs from `start`, the end
    of the stage before, to its final_time (time runs on across stages)."""
    spec = mapping(value, where, ("type", "dt", "final_time", "newmark", "mass", "modes", "tie", "scheme", "alpha", "rho_inf"),
                   required=("type",) if where != "analysis" else ())
    a = Analysis()
    a.type = string(spec.get("type", a.type), f"{where}.type",
                    choices=("static", "dynamic", "modal") if where == "analysis" else ("static", "dynamic"))
    a.mass = string(spec.get("mass", a.mass), f"{where}.mass", choices=("consistent", "lumped"))
    if a.type == "modal":
        for key in ("dt", "final_time", "newmark", "scheme", "alpha", "rho_inf"):
            if key in spec:
                raise InputError(f"{where}.{key}: a modal analysis has no time steps")
        a.modes = integer(spec.get("modes", a.modes), f"{where}.modes", ge=1, le=10000)
        a.tie = boolean(spec.get("tie", a.tie), f"{where}.tie")
        return a
    for key in ("modes", "tie"):
        if key in spec:
            raise InputError(f"{where}.{key}: only for a modal analysis (type: modal)")
    if a.type == "dynamic":
        for key in ("dt", "final_time"):
            if key not in spec:
                raise InputError(f"{where}.{key}: required for a dynamic analysis")
    # Static: dt and the stage's length (final_time - start) default to each other, both to 1
    # (one load step).
    if "final_time" in spec:
        a.final_time = real(spec["final_time"], f"{where}.final_time")
        if not a.final_time > start:
            raise InputError(f"{where}.final_time: must be > {start:g}, where the stage before ends, "
                             f"got {a.final_time:g}")
    a.dt = real(spec.get("dt", a.final_time - start if "final_time" in spec else 1.0), f"{where}.dt", gt=0)
    if "final_time" not in spec:
        a.final_time = start + a.dt
    length = a.final_time - start
    if length < a.dt * (1 - 1e-12):
        raise InputError(f"{where}.final_time: must be >= {'the start ' + format(start, 'g') + ' + ' if start else ''}"
                         f"dt = {start + a.dt:g}, got {a.final_time:g}")
    if length / a.dt > MAX_STEPS:
        raise InputError(f"{where}.dt: {a.dt:g} to final_time {a.final_time:g} is {length / a.dt:.3g} "
                         f"steps, more than {MAX_STEPS:g}")
    a.scheme = string(spec.get("scheme", a.scheme), f"{where}.scheme", choices=SCHEMES)
    for key, scheme in (("alpha", "hht"), ("rho_inf", "generalized_alpha")):
        if key in spec and a.scheme != scheme:
            raise InputError(f"{where}.{key}: only with scheme: {scheme}")
    if "newmark" in spec and a.scheme != "newmark":
        raise InputError(f"{where}.newmark: the {a.scheme} scheme sets beta and gamma itself")
    newmark = mapping(spec.get("newmark"), f"{where}.newmark", ("beta", "gamma"))
    a.newmark_beta = real(newmark.get("beta", a.newmark_beta), f"{where}.newmark.beta", gt=0)
    a.newmark_gamma = real(newmark.get("gamma", a.newmark_gamma), f"{where}.newmark.gamma", gt=0)
    if a.scheme == "hht":  # Hilber-Hughes-Taylor in Code_Aster's sign: alpha_f = -alpha, alpha_m = 0
        a.alpha = real(spec.get("alpha", a.alpha), f"{where}.alpha")
        if not -1.0 / 3.0 - 1e-12 <= a.alpha <= 0:
            raise InputError(f"{where}.alpha: HHT's alpha must lie in [-1/3, 0] (0: the trapezoidal rule), got {a.alpha:g}")
        a.alpha_m, a.alpha_f = 0.0, -a.alpha
    elif a.scheme == "generalized_alpha":  # Chung and Hulbert (1993)
        a.rho_inf = real(spec.get("rho_inf", a.rho_inf), f"{where}.rho_inf", ge=0)
        if a.rho_inf > 1:
            raise InputError(f"{where}.rho_inf: the spectral radius at infinite frequency lies in [0, 1], got {a.rho_inf:g}")
        a.alpha_m = (2 * a.rho_inf - 1) / (a.rho_inf + 1)
        a.alpha_f = a.rho_inf / (a.rho_inf + 1)
    if a.scheme != "newmark":
        a.newmark_gamma = 0.5 - a.alpha_m + a.alpha_f
        a.newmark_beta = 0.25 * (1 - a.alpha_m + a.alpha_f) ** 2
    stable = a.newmark_gamma >= 0.5 and a.newmark_beta >= (a.newmark_gamma + 0.5) ** 2 / 4 * (1 - 1e-12)
    if a.type == "dynamic" and not stable:
        warn(f"{where}.newmark: beta={a.newmark_beta:g}, gamma={a.newmark_gamma:g} is not "
             "unconditionally stable (needs gamma >= 0.5 and beta >= (gamma + 0.5)^2 / 4)")
    return a


def _stages(value, loads, body_names, base_dir):
    """The stages in order, each from the end of the one before; a stage's `loads` join those
    acting already (top-level loads act from the first stage) and keep acting to the end. The
    loads of stage i are appended to `loads` with load.stage = i."""
    if not isinstance(value, list) or not value:
        raise InputError(f"stages: expected a non-empty list of stages (lines starting with '- '), "
                         f"got {_describe(value)}")
    stages, names, start, steps = [], {}, 0.0, 0.0
    for i, spec in enumerate(value):
        where = f"stages[{i}]"
        spec = mapping(spec, where, ("name", "analysis", "loads"), required=("analysis",))
        name = string(spec.get("name", f"stage{i}"), f"{where}.name")
        if name in names:
            raise InputError(f"{where}.name: stage '{name}' is already stages[{names[name]}]")
        names[name] = i
        a = _analysis(spec["analysis"], f"{where}.analysis", start)
        if stages and a.mass != stages[0].analysis.mass:
            raise InputError(f"{where}.analysis.mass: every stage uses one mass matrix "
                             f"({stages[0].analysis.mass} in stages[0]), got {a.mass}")
        for j, e in enumerate(entries(spec.get("loads"), f"{where}.loads")):
            for load in _loads(e, f"{where}.loads[{j}]", body_names, base_dir):
                load.stage = i
                loads.append(load)
        steps += (a.final_time - start) / a.dt
        if steps > MAX_STEPS:
            raise InputError(f"{where}.analysis.dt: the stages up to this one make {steps:.3g} steps, "
                             f"more than {MAX_STEPS:g}")
        stages.append(Stage(name, a, start))
        start = a.final_time
    return stages


def _output(value, body_names):
    spec = mapping(value, "output", ("every", "fields", "energy", "points"))
    out = Output()
    out.every = integer(spec.get("every", out.every), "output.every", ge=1)
    fields = spec.get("fields", out.fields)
    fields = [fields] if isinstance(fields, str) else fields
    if not isinstance(fields, list):
        raise InputError(f"output.fields: expected a list of {', '.join(FIELDS)}, got {fields!r}")
    out.fields = [string(f, "output.fields", choices=FIELDS) for f in fields]
    out.fields = [f for f in FIELDS if f in out.fields]  # canonical order, no repeats
    out.energy = boolean(spec.get("energy", out.energy), "output.energy")
    points = named(spec.get("points"), "output.points")
    out.points = [_point(name, p, f"output.points.{name}", body_names) for name, p in points.items()]
    return out


def _point(name, value, where, body_names):
    """[x, y, z] or {x: [x, y, z], body: name}."""
    string(name, where)
    if not isinstance(value, dict):
        return Point(name, vector3(value, where), "")
    spec = mapping(value, where, ("x", "body"), required=("x",))
    body = string(spec["body"], f"{where}.body") if "body" in spec else ""
    if body and body not in body_names:
        raise InputError(f"{where}.body: unknown body {body!r} (bodies: {', '.join(body_names)})")
    return Point(name, vector3(spec["x"], f"{where}.x"), body)


def _surface_references(doc, couples, dirichlet, loads, added_mass=(), absorbing=()):
    """Referenced surface names in order of first appearance in the file.

    Sections are visited in the order they appear in the YAML; within a couple
    the master names come before the slave names.
    """
    refs = {}

    def add(name, where):
        refs.setdefault(name, []).append(where)

    for section in doc:
        if section == "couples":
            for i, c in enumerate(couples):
                for side in ("master", "slave"):
                    for name in getattr(c, side):
                        add(name, f"couples[{i}].{side} (couple k={c.k})")
        elif section == "dirichlet":
            for i, d in enumerate(dirichlet):
                if d.surface:
                    add(d.surface, f"dirichlet[{i}].surface")
        elif section in ("loads", "stages"):
            for load in loads:
                if load.surface and load.where.startswith("stages") == (section == "stages"):
                    add(load.surface, f"{load.where}.surface")
        elif section == "added_mass":
            for i, m in enumerate(added_mass):
                add(m.surface, f"added_mass[{i}].surface")
        elif section == "absorbing":
            for i, x in enumerate(absorbing):
                add(x.surface, f"absorbing[{i}].surface")
    return refs
