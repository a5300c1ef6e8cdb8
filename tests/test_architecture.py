"""The layout shows the architecture (docs/architecture.md): the pure-JAX core imports nothing
from the edge (cases, files, plots, command line, workflows, data sets), and no module (tests
included) imports another bearingsim module's private names.  Read from the source with ast."""
import ast
import re
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "bearingsim"

#: the folders, in the order of the flow, and the folders each may import (besides itself and the
#: top-level infrastructure).  The core (physics, signals, dynamics) imports nothing of the edge.
FOLDERS = {
    "physics": set(),
    "dynamics": {"physics"},
    "signals": {"physics", "dynamics"},
    "case": {"physics", "dynamics", "signals"},    # the built scenario holds DynamicsParameters, Background
    "output": {"physics", "signals", "dynamics", "case"},
    "datasets": {"physics", "signals", "dynamics", "case", "output"},
    "realism": {"physics", "signals", "dynamics", "case", "output", "datasets"},
    "app": {"physics", "signals", "dynamics", "case", "output", "datasets", "realism"},
}
CORE = {"physics", "signals", "dynamics"}
EDGE = set(FOLDERS) - CORE
#: the top-level modules: start-up and the vocabulary every layer shares (no folder's module)
INFRASTRUCTURE = {"__init__", "_version", "runtime", "errors", "names", "keys", "xla", "programs", "warm", "fastmath", "hostarrays"}


def stage(path: Path) -> str:
    """Folder of a file under bearingsim/ (bearingsim/case/schema.py -> "case"), or the module's
    name for a top-level module (bearingsim/errors.py -> "errors")."""
    parts = path.relative_to(PACKAGE).with_suffix("").parts
    return parts[0]


def module_name(path: Path) -> str:
    """bearingsim/physics/jones.py -> "physics.jones"; bearingsim/errors.py -> "errors"."""
    parts = path.relative_to(PACKAGE).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


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
                # "from . import io" imports the module bearingsim.output.io
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
    f.write_text("import numpy\nfrom bearingsim.physics.jones import _solve, solve\nfrom bearingsim.output import io\n"
                 "def g():\n    from ..errors import InputError\n    from .units import _x\n")
    assert [(t, n) for _, t, n in imports(f, "bearingsim.case.schema")] == [
        ("bearingsim.physics.jones", "_solve"), ("bearingsim.physics.jones", "solve"), ("bearingsim.output.io", None),
        ("bearingsim.errors", "InputError"), ("bearingsim.case.units", "_x")]
    assert private_imports([f], lambda p: "bearingsim.case.schema") == [
        f"{f}:2 imports bearingsim.physics.jones._solve", f"{f}:6 imports bearingsim.case.units._x"]


def test_the_folders_show_the_flow():
    """ls bearingsim/ shows the folders of the flow and the infrastructure only (issue 27 item 7)."""
    top = {p.stem for p in PACKAGE.glob("*.py")}
    folders = {p.name for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    assert top == INFRASTRUCTURE, f"top-level modules outside the infrastructure: {sorted(top - INFRASTRUCTURE)}"
    assert folders == set(FOLDERS), sorted(folders ^ set(FOLDERS))


def test_each_folder_imports_only_the_folders_before_it():
    bad = []
    for p in sources():
        own = stage(p)
        allowed = (FOLDERS.get(own, set()) | {own} | INFRASTRUCTURE) if own not in INFRASTRUCTURE else INFRASTRUCTURE
        for line, target, _ in imports(p, dotted(p)):
            parts = target.split(".")
            if len(parts) > 1 and parts[1] not in allowed:
                bad.append(f"{p.relative_to(ROOT)}:{line} ({own}) imports {target}")
    assert not bad, "imports against the flow:\n" + "\n".join(bad)


def test_core_imports_nothing_from_the_edge():
    bad = []
    for p in sources():
        if stage(p) not in CORE:
            continue
        for line, target, _ in imports(p, dotted(p)):
            parts = target.split(".")
            if len(parts) > 1 and parts[1] in EDGE:
                bad.append(f"{p.relative_to(ROOT)}:{line} imports {target}")
    assert not bad, "the core imports the edge:\n" + "\n".join(bad)


def test_the_package_root_imports_only_the_infrastructure():
    init = PACKAGE / "__init__.py"
    found = [t for _, t, _ in imports(init, "bearingsim") if len(t.split(".")) > 1 and t.split(".")[1] not in INFRASTRUCTURE]
    assert not found, f"importing bearingsim pulls in: {found}"


def test_the_old_flat_paths_are_gone():
    """The flat paths before the folders (bearingsim.jones, bearingsim.signal, ...) warned for a
    release (bearingsim.moved) and are removed (issue 35): an old path is not importable and is no
    attribute of the package, so a stale import fails at once instead of warning."""
    import importlib
    import sys

    import bearingsim

    for old in ("jones", "signal", "workflows"):
        sys.modules.pop(f"bearingsim.{old}", None)
        with pytest.raises(ModuleNotFoundError):
            importlib.import_module(f"bearingsim.{old}")
        with pytest.raises(AttributeError):
            getattr(bearingsim, old)
    assert not (PACKAGE / "moved.py").exists()


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
    for n in sorted({module_name(p) for p in sources()})])
def test_no_module_imports_private_names(name):
    paths = [p for p in sources() if module_name(p) == name]
    assert paths
    bad = private_imports(paths, dotted)
    assert not bad, "\n".join(bad)


def module_graph():
    """Module -> the set of bearingsim modules it imports (any depth in the file); a package's
    __init__ counts as its folder's module (dynamics, case, datasets: one concept each)."""
    def unit(dotted_name):
        parts = dotted_name.split(".")[1:]
        return ".".join(parts[:2]) if parts and parts[0] in FOLDERS and parts[0] not in ("dynamics", "case") \
            else (parts[0] if parts else "")

    graph = {}
    for p in sources():
        if stage(p) in INFRASTRUCTURE:
            continue
        own = unit(dotted(p))
        for _, target, _ in imports(p, dotted(p)):
            t = unit(target)
            if t and t != own and t.split(".")[0] not in INFRASTRUCTURE and t not in FOLDERS:
                graph.setdefault(own, set()).add(t)
    return graph


def test_no_two_modules_import_each_other():
    g = module_graph()
    pairs = sorted({tuple(sorted((a, b))) for a, deps in g.items() for b in deps if a in g.get(b, set())})
    assert not pairs, "modules that import each other: " + ", ".join(f"{a} <-> {b}" for a, b in pairs)


#: the start-up seams (bearingsim/...): ``import bearingsim`` (lazy exports) and the command line
#: (its ``_Lazy`` loaders: ``bearingsim --help`` loads no JAX) import bearingsim modules at first use
SEAMS = {"__init__.py", "app/lazy_modules.py"}
#: function-local imports of bearingsim modules outside the seams, at most; each gives its reason
MAX_LOCAL_IMPORTS = 10
#: files whose function-local imports are still to move to the top (issue 35 item 4; edited by the
#: transfer work at the time); each must go from this table, not grow it
LOCAL_IMPORTS_NOT_YET_MOVED = set()


def function_local_imports(path: Path) -> list:
    """Lines of the imports of bearingsim modules (relative, or ``bearingsim...``) inside a function
    of ``path``, sorted."""
    found = set()
    for f in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        for n in ast.walk(f):
            if isinstance(n, ast.ImportFrom) and (n.level or (n.module or "").split(".")[0] == "bearingsim"):
                found.add(n.lineno)
            elif isinstance(n, ast.Import) and any(a.name.split(".")[0] == "bearingsim" for a in n.names):
                found.add(n.lineno)
    return sorted(found)


def local_reason(lines: list, line: int) -> bool:
    """Whether the import on ``line`` (1-based) gives its reason: a ``# local:`` comment on that
    line, or on the comment lines directly above it (one comment may head a run of imports)."""
    k = line - 1
    if "# local:" in lines[k]:
        return True
    for text in (s.strip() for s in reversed(lines[:k])):
        if "# local:" in text:
            return True
        if not text.startswith(("#", "from ", "import ")):
            return False
    return False


def test_the_local_import_scanner(tmp_path):
    f = tmp_path / "t.py"
    f.write_text("from . import a\nimport numpy\n"
                 "def g():\n    import numpy\n    from .b import c\n"
                 "    # local: a reason\n    # said over two lines\n    from ..d import e\n    import bearingsim.f\n"
                 "    x = 1\n    from .g import h  # local: another\n"
                 "class K:\n    def m(self):\n        import bearingsim\n")
    lines = f.read_text().splitlines()
    assert function_local_imports(f) == [5, 8, 9, 11, 14]
    assert [local_reason(lines, n) for n in (5, 8, 9, 11, 14)] == [False, True, True, True, False]


def test_function_local_imports_only_at_the_seams():
    """Issue 35 item 4: a module imports the bearingsim modules it needs at its top, where a reader
    and the flow tests above see them.  Laziness belongs to the start-up seams (:data:`SEAMS`);
    elsewhere a function-local import needs its reason on a ``# local:`` comment (a heavy optional
    library only one path needs, a module documented to load no JAX), at most
    :data:`MAX_LOCAL_IMPORTS` of them in the package."""
    local, unexplained = [], []
    for p in sources():
        rel = p.relative_to(PACKAGE).as_posix()
        if rel in SEAMS or rel in LOCAL_IMPORTS_NOT_YET_MOVED:
            continue
        lines = p.read_text(encoding="utf-8").splitlines()
        for line in function_local_imports(p):
            where = f"bearingsim/{rel}:{line}: {lines[line - 1].strip()}"
            local.append(where)
            if not local_reason(lines, line):
                unexplained.append(where)
    assert not unexplained, ("import these at the top of the module (or give the reason on a "
                             "'# local: ...' comment):\n" + "\n".join(unexplained))
    assert len(local) <= MAX_LOCAL_IMPORTS, (f"{len(local)} function-local imports of bearingsim modules "
                                             f"(at most {MAX_LOCAL_IMPORTS}):\n" + "\n".join(local))


#: the data set package's files in the order of its flow: each imports only those before it
DATASET_FLOW = ("spec", "program", "writer", "runner")


def test_the_dataset_package_shows_the_flow():
    """spec (labels) -> program (the device program) -> writer (chunk files, HDF5) -> runner
    (plan, device, in-process / Dask, make_dataset): no file imports a later one."""
    files = {p.stem for p in (PACKAGE / "datasets").glob("*.py")} - {"__init__"}
    assert set(DATASET_FLOW) <= files
    for k, name in enumerate(DATASET_FLOW):
        p = PACKAGE / "datasets" / f"{name}.py"
        later = {f"bearingsim.datasets.{n}" for n in DATASET_FLOW[k + 1:]}
        bad = [t for _, t, _ in imports(p, dotted(p)) if t in later]
        assert not bad, f"datasets/{name}.py imports a later stage: {bad}"


def test_the_command_line_has_no_set_branch():
    """Sets go through bearingsim.app.workflows like single bearings (issue 27 item 7): the workflow
    entries dispatch on the case, so cli.py neither asks whether a case is a set nor imports the
    set edge module."""
    for name in ("cli", "commands"):
        path = PACKAGE / "app" / f"{name}.py"
        src = path.read_text(encoding="utf-8")
        assert "is_set" not in src
        assert not [t for _, t, _ in imports(path, f"bearingsim.app.{name}")
                    if t in ("bearingsim.app.set_workflows", "bearingsim.output.set_report", "bearingsim.output.plots_set")]


def test_the_newton_machinery_lives_in_one_module():
    """The damped Newton's constants, step cap, step status and batch retry are defined once, in
    bearingsim.physics.newton, below jones and shaft (issue 27 item 7)."""
    shared = ("_LS_STEPS", "_FREE_STEPS", "_RING_CAP", "_BALL_CAP", "def _cap(", "def newton_step_status(",
              "n_pad = 1 <<", "def _traced(", "def _tolerances(")
    found = [f"{p.relative_to(ROOT)}: {s}" for p in sources() if p.name != "newton.py"
             for s in shared if s in p.read_text(encoding="utf-8")]
    assert not found, "\n".join(found)
    for user in ("jones", "shaft"):
        assert ("bearingsim.physics.newton" in {t for _, t, _ in imports(PACKAGE / "physics" / f"{user}.py",
                                                                         f"bearingsim.physics.{user}")})


#: files (patterns relative to bearingsim/) allowed a bare ValueError / TypeError: none (issue 35);
#: every module raises the project's own errors (bearingsim.errors: InputError, InputTypeError, ...)
NOT_YET_CONVERTED = set()


def bare_raises(path: Path):
    """(line, name) of every ``raise ValueError(...)`` / ``raise TypeError(...)`` (or without the
    call) in ``path``; the project's own errors (bearingsim.errors) subclass both."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Raise) or node.exc is None:
            continue
        exc = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
        if isinstance(exc, ast.Name) and exc.id in ("ValueError", "TypeError"):
            out.append((node.lineno, exc.id))
    return sorted(out)


def test_the_raise_scanner_finds_bare_value_and_type_errors(tmp_path):
    f = tmp_path / "t.py"
    f.write_text("def f(x):\n    if x:\n        raise ValueError('x')\n    raise TypeError\n"
                 "def g():\n    try:\n        pass\n    except ValueError:\n        raise\n"
                 "    raise InputError('x', 'hint')\n")
    assert bare_raises(f) == [(3, "ValueError"), (4, "TypeError")]


def test_no_bare_value_or_type_error():
    """Every error a user can reach is the project's own (issue 35 item 3): a BearingsimError
    has a message, a hint and an exit code, and the command line prints it as one line (a bare
    ValueError would print a traceback)."""
    from fnmatch import fnmatch

    bad = []
    for p in sources():
        rel = p.relative_to(PACKAGE).as_posix()
        if any(fnmatch(rel, pat) for pat in NOT_YET_CONVERTED):
            continue
        bad += [f"bearingsim/{rel}:{line} raises a bare {name}" for line, name in bare_raises(p)]
    assert not bad, ("raise bearingsim.errors.InputError(message, hint) (InputTypeError for a wrong type) "
                     "instead:\n" + "\n".join(bad))


def test_one_definition_of_the_fault_classes():
    """Issue 35: the fault classes and their numbers are defined once (bearingsim/names.py:
    CLASSES, CLASS_NUMBER); every other module imports them.  Fails on any other module-level
    assignment of a name ending in CLASSES to a tuple of class names."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if not isinstance(node, ast.Assign):
                continue
            for t in node.targets:
                if isinstance(t, ast.Name) and t.id.endswith("CLASSES") and "healthy" in ast.unparse(node.value):
                    found.append(f"{path.relative_to(PACKAGE)} {t.id}")
    assert found == ["names.py CLASSES"], found


#: the per-frequency keys of the results files and data set labels
FREQUENCY_KEYS = {"shaft_Hz", "ftf_Hz", "bpfo_Hz", "bpfi_Hz", "bsf_Hz"}


def frequency_shapes(path: Path):
    """(line, what) of every in-memory frequency container in ``path`` other than
    DefectFrequencies: a dict literal or ``dict(...)`` call keyed mostly (half its keys or more,
    two at least) by :data:`FREQUENCY_KEYS` (a table of label columns that includes some is not
    one), or a class with ``bpfo`` and ``bpfi`` fields."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        keys = set()
        if isinstance(node, ast.Dict):
            keys = {k.value for k in node.keys if isinstance(k, ast.Constant)}
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "dict":
            keys = {k.arg for k in node.keywords}
        n = len(keys & FREQUENCY_KEYS)
        if n >= 2 and 2 * n >= len(keys):
            yield node.lineno, "a dict of defect frequencies"
        if isinstance(node, ast.ClassDef) and node.name != "DefectFrequencies":
            fields = {t.target.id for t in node.body if isinstance(t, ast.AnnAssign) and isinstance(t.target, ast.Name)}
            if {"bpfo", "bpfi"} <= fields:
                yield node.lineno, f"class {node.name} with bpfo and bpfi fields"


def test_the_frequency_scanner_finds_other_shapes(tmp_path):
    p = tmp_path / "m.py"
    p.write_text("a = {'bpfo_Hz': 1.0, 'bpfi_Hz': 2.0}\nb = dict(shaft_Hz=1, ftf_Hz=2)\n"
                 "class F:\n    bpfo: float\n    bpfi: float\nc = {'bpfo_Hz': 1}\n")
    assert sorted(line for line, _ in frequency_shapes(p)) == [1, 2, 3]
    p.write_text("labels = {'bpfo_Hz': 1, 'bpfi_Hz': 2, 'index': 0, 'speed_rpm': 1, 'split': 0}\n")
    assert list(frequency_shapes(p)) == []


def test_one_frequency_type():
    """Issue 35 item 3: every result that reports defect frequencies holds a
    ``physics.kinematics.DefectFrequencies`` (its ``hz()`` / ``from_hz`` convert to and from the
    ``*_Hz`` fields of files and labels); no module builds a dict or a class of its own."""
    found = [f"bearingsim/{p.relative_to(PACKAGE).as_posix()}:{line}: {what}"
             for p in sources() for line, what in frequency_shapes(p)]
    assert not found, "use DefectFrequencies instead:\n" + "\n".join(found)


#: the modules allowed over :data:`MAX_LINES` lines, each one job (docs/architecture.md, "Module sizes")
LONG_MODULES = {"physics/shaft.py", "physics/jones.py", "case/schema.py"}
MAX_LINES = 450


def test_modules_stay_small():
    """Issue 35: a module does one job and stays under 450 lines; the three listed (with their
    reasons in docs/architecture.md) are the exceptions, and the list may only shrink."""
    long = {p.relative_to(PACKAGE).as_posix() for p in sources()
            if len(p.read_text(encoding="utf-8").splitlines()) > MAX_LINES}
    assert long <= LONG_MODULES, f"over {MAX_LINES} lines: {sorted(long - LONG_MODULES)} (split by job)"
    assert len(LONG_MODULES) <= 3


#: the modules that take a built scenario (``case.build()``, issue 35 item 1): the data set engine,
#: the signal workflows, the rig records, identify and the record spectra read its fields, never the
#: case API (the case's accessors build a new object at every call; a scenario is built once)
SCENARIO_TAKERS = ("datasets/spec.py", "datasets/program.py", "datasets/runner.py", "datasets/writer.py",
                   "app/signal_workflows.py", "app/set_workflows.py", "realism/rig_record.py", "realism/identify.py",
                   "realism/record_spectrum.py")
CASE_API = re.compile(r"\.(dynamics_settings|dataset_settings|limits_settings|sweep_settings|bearing|operation|loads|"
                      r"spall|bearing_set)\(\)|\.si\(|\.data\[|\.data\.get\(|\.raw\b")


def test_the_engine_takes_a_built_scenario_not_the_case_api():
    bad = []
    for rel in SCENARIO_TAKERS:
        for n, line in enumerate((PACKAGE / rel).read_text().splitlines(), 1):
            code = line.split("#")[0]
            if CASE_API.search(code) and not code.strip().startswith(('"', "'", "``")):
                bad.append(f"{rel}:{n}: {line.strip()}")
    assert not bad, "the case API read below a workflow's entry (take the Scenario's fields):\n" + "\n".join(bad)


#: a result code compared by hand with an integer (issue 35 item 3): use errors.succeeded / failed
HAND_COMPARED = re.compile(r"\b(?:result|code|codes)\b[\s\"'\]\)]*[!=]=\s*0\b")


def code_only(path: Path) -> dict:
    """line -> the line's code with every string literal emptied and comments dropped (tokenize)."""
    out = {}
    with open(path, "rb") as fh:
        for tok in tokenize.tokenize(fh.readline):
            if tok.type in (tokenize.COMMENT, tokenize.ENCODING, tokenize.NL, tokenize.NEWLINE):
                continue
            text = '""' if tok.type == tokenize.STRING or tok.type == getattr(tokenize, "FSTRING_MIDDLE", -1) \
                else tok.string
            out[tok.start[0]] = out.get(tok.start[0], "") + " " + text
    return out


def test_the_code_scanner_skips_strings_and_comments(tmp_path):
    f = tmp_path / "m.py"
    f.write_text('"""result != 0 in a docstring"""\nx = sol.result != 0  # result == 0\ny = "result == 0"\n')
    lines = code_only(f)
    assert [n for n, c in lines.items() if HAND_COMPARED.search(c)] == [2]


def test_result_codes_are_not_compared_with_integers_by_hand():
    bad = []
    for p in PACKAGE.rglob("*.py"):
        for n, code in code_only(p).items():
            if HAND_COMPARED.search(code):
                bad.append(f"{p.relative_to(ROOT)}:{n}: {code.strip()}")
    assert not bad, "result codes compared with integers (use bearingsim.errors.succeeded / failed):\n" + "\n".join(bad)
