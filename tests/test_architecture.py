"""The layout shows the architecture (docs/architecture.md): the pure-JAX core imports nothing
from the edge (cases, files, plots, command line, workflows, data sets), and no module (tests
included) imports another bearingsim module's private names.  Read from the source with ast."""
import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "bearingsim"

#: the edge: reads and writes files, converts units, draws, reports; everything else is the core
EDGE = {"case", "io", "plots", "plots_signal", "cli", "workflows", "dataset", "report", "realism",
        "calibration", "transfer", "machine", "records", "distributed", "budget", "sets", "mldata",
        "record_spectrum", "identify"}
#: the core modules the architecture names (a new module is core unless listed in EDGE)
CORE = {"geometry", "hertz", "kinematics", "defect", "balls", "jones", "sweep", "dynamics", "signal", "errors", "xla", "fastmath",
        "pit", "passes", "features", "background", "life", "limits", "background_fit", "shaft",
        "signal_stage", "nuisance", "fault_size", "names", "newton", "keys"}
INFRASTRUCTURE = {"__init__", "_version", "runtime"}


def stage(path: Path) -> str:
    """Top-level module of a file under bearingsim/: bearingsim/case/schema.py -> "case"."""
    parts = path.relative_to(PACKAGE).with_suffix("").parts
    return parts[0]


def dotted(path: Path) -> str:
    parts = ("bearingsim",) + path.relative_to(PACKAGE).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path, module: str | None):
    """(line, imported module, imported name or None) for every import of a bearingsim module in
    ``path`` (``module``: its dotted name, for relative imports; None outside the package)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    is_package = path.name == "__init__.py"
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "bearingsim":
                    yield node.lineno, a.name, None
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".")
                base = base[:len(base) - node.level + (1 if is_package else 0)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "bearingsim":
                continue
            for a in node.names:
                # "from . import io" imports the module bearingsim.io
                sub = f"{target}.{a.name}"
                if (PACKAGE.parent / Path(*sub.split("."))).with_suffix(".py").exists() or \
                        (PACKAGE.parent / Path(*sub.split("."))).is_dir():
                    yield node.lineno, sub, None
                else:
                    yield node.lineno, target, a.name


def sources():
    return sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


def test_the_scanner_resolves_absolute_and_relative_imports(tmp_path):
    f = tmp_path / "t.py"
    f.write_text("import numpy\nfrom bearingsim.jones import _solve, solve\nfrom bearingsim import io\n"
                 "def g():\n    from ..errors import InputError\n    from .units import _x\n")
    assert [(t, n) for _, t, n in imports(f, "bearingsim.case.schema")] == [
        ("bearingsim.jones", "_solve"), ("bearingsim.jones", "solve"), ("bearingsim.io", None),
        ("bearingsim.errors", "InputError"), ("bearingsim.case.units", "_x")]
    assert private_imports([f], lambda p: "bearingsim.case.schema") == [
        f"{f}:2 imports bearingsim.jones._solve", f"{f}:6 imports bearingsim.case.units._x"]


def test_the_named_modules_exist():
    found = {stage(p) for p in sources()}
    assert EDGE <= found and CORE <= found and not (EDGE & CORE)


def test_core_imports_nothing_from_the_edge():
    bad = []
    for p in sources():
        if stage(p) in EDGE or stage(p) in INFRASTRUCTURE:
            continue
        for line, target, _ in imports(p, dotted(p)):
            parts = target.split(".")
            if len(parts) > 1 and parts[1] in EDGE:
                bad.append(f"{p.relative_to(ROOT)}:{line} imports {target}")
    assert not bad, "the core imports the edge:\n" + "\n".join(bad)


def test_the_package_root_imports_only_the_core():
    init = PACKAGE / "__init__.py"
    edge = [t for _, t, _ in imports(init, "bearingsim") if len(t.split(".")) > 1 and t.split(".")[1] in EDGE]
    assert not edge, f"importing bearingsim pulls in the edge: {edge}"


def private_imports(paths, module_of):
    bad = []
    for p in paths:
        own = module_of(p)
        for line, target, name in imports(p, own):
            if name and name.startswith("_") and not name.startswith("__") and target != own:
                where = p.relative_to(ROOT) if p.is_relative_to(ROOT) else p
                bad.append(f"{where}:{line} imports {target}.{name}")
    return bad


def test_tests_import_no_private_names():
    tests = sorted((ROOT / "tests").rglob("*.py"))
    bad = private_imports(tests, lambda p: None)
    assert not bad, "\n".join(bad)


#: modules still importing private names; each must go from this table, not grow it
_MID_REFACTOR: dict = {}   # modules allowed to import private names while mid-refactor (none)


@pytest.mark.parametrize("name", [
    pytest.param(n, marks=pytest.mark.xfail(strict=False, reason=_MID_REFACTOR[n])) if n in _MID_REFACTOR else n
    for n in sorted(EDGE | CORE | {p.stem for p in PACKAGE.glob("*.py")} - INFRASTRUCTURE)])
def test_no_module_imports_private_names(name):
    paths = [p for p in sources() if stage(p) == name]
    assert paths
    bad = private_imports(paths, dotted)
    assert not bad, "\n".join(bad)


def module_graph():
    """Top-level module -> the set of top-level bearingsim modules it imports (any depth)."""
    graph = {}
    for p in sources():
        own = stage(p)
        if own in INFRASTRUCTURE:
            continue
        for _, target, _ in imports(p, dotted(p)):
            parts = target.split(".")
            if len(parts) > 1 and parts[1] != own and parts[1] not in INFRASTRUCTURE:
                graph.setdefault(own, set()).add(parts[1])
    return graph


def test_no_two_modules_import_each_other():
    g = module_graph()
    pairs = sorted({tuple(sorted((a, b))) for a, deps in g.items() for b in deps if a in g.get(b, set())})
    assert not pairs, "modules that import each other: " + ", ".join(f"{a} <-> {b}" for a, b in pairs)


#: the data set package's files in the order of its flow: each imports only those before it
DATASET_FLOW = ("spec", "program", "writer", "runner")


def test_the_dataset_package_shows_the_flow():
    """spec (labels) -> program (the device program) -> writer (chunk files, HDF5) -> runner
    (plan, device, in-process / Dask, make_dataset): no file imports a later one."""
    files = {p.stem for p in (PACKAGE / "dataset").glob("*.py")} - {"__init__"}
    assert files == set(DATASET_FLOW)
    for k, name in enumerate(DATASET_FLOW):
        p = PACKAGE / "dataset" / f"{name}.py"
        later = {f"bearingsim.dataset.{n}" for n in DATASET_FLOW[k + 1:]}
        bad = [t for _, t, _ in imports(p, dotted(p)) if t in later]
        assert not bad, f"dataset/{name}.py imports a later stage: {bad}"


def test_the_command_line_has_no_set_branch():
    """Sets go through bearingsim.workflows like single bearings (issue 27 item 7): the workflow
    entries dispatch on the case, so cli.py neither asks whether a case is a set nor imports the
    set edge module."""
    path = PACKAGE / "cli.py"
    src = path.read_text(encoding="utf-8")
    assert "is_set" not in src
    assert not [t for _, t, _ in imports(path, "bearingsim.cli") if t == "bearingsim.sets"]


def test_the_newton_machinery_lives_in_one_module():
    """The damped Newton's constants, step cap, step status and batch retry are defined once, in
    bearingsim.newton, below jones and shaft (issue 27 item 7)."""
    shared = ("_LS_STEPS", "_FREE_STEPS", "_RING_CAP", "_BALL_CAP", "def _cap(", "def newton_step_status(",
              "n_pad = 1 <<", "def _traced(", "def _tolerances(")
    found = [f"{p.relative_to(ROOT)}: {s}" for p in sources() if p.name != "newton.py"
             for s in shared if s in p.read_text(encoding="utf-8")]
    assert not found, "\n".join(found)
    for user in ("jones", "shaft"):
        assert ("bearingsim.newton" in {t for _, t, _ in imports(PACKAGE / f"{user}.py", f"bearingsim.{user}")})
