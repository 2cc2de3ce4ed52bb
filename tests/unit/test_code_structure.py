"""Structure rules of the code base, checked statically (no imports of the code under test).

* No import cycles between modules, function-level imports included (they hid two).
* Every topic name and QoS profile comes from ``bearing_common.topics``: no topic-name
  string literal and no ``QoSProfile(...)`` anywhere else.
* The observer and diagnoser packages import nothing from ``bearing_sim``, so they run on a
  machine without the simulator (tested for real in ``test_runs_without_bearing_sim``).
* The diagnoser by front end: its decision core imports neither front end, the front ends
  import each other not, one module picks between them (and names them: no comparison with
  "spectral" or "fold" anywhere else), and the diagnoser reaches into the observer package
  only where it runs the observers' sessions offline (:mod:`bearing_diagnoser.pipeline`).
"""

from __future__ import annotations

import ast
import pathlib
import subprocess
import sys

from bearing_common import topics

ROOT = pathlib.Path(__file__).resolve().parents[2]
PACKAGES = sorted(p.parent.name for p in (ROOT / "src").glob("*/setup.py"))
PYTHON_DIRS = [ROOT / "src", ROOT / "tests", ROOT / "benchmarks", ROOT / "tools"]


def source_files(dirs=PYTHON_DIRS):
    for d in dirs:
        for path in sorted(d.rglob("*.py")):
            if "__pycache__" not in path.parts:
                yield path


def module_name(path: pathlib.Path) -> str | None:
    """Dotted name of a module inside one of our packages, else None."""
    rel = path.relative_to(ROOT / "src")
    parts = list(rel.with_suffix("").parts)
    if len(parts) < 3 or parts[0] != parts[1]:
        return None  # setup.py, launch files
    name = ".".join(parts[1:])
    return name[: -len(".__init__")] if name.endswith(".__init__") else name


def imported_modules(path: pathlib.Path, name: str, known: set) -> set:
    """Our modules that ``name`` imports anywhere in its body (function-level included)."""
    tree = ast.parse(path.read_text(), str(path))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(tree):
        targets = []
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")
                up = up[: len(up) - (node.level - 1)]
                base = ".".join(up + ([base] if base else []))
            targets = [f"{base}.{a.name}" for a in node.names] + [base]
        for t in targets:
            while t and t not in known:
                t = t.rpartition(".")[0]
            if t and t != name:
                found.add(t)
    return found


def import_graph() -> dict:
    files = {module_name(p): p for p in source_files([ROOT / "src"]) if module_name(p)}
    known = set(files)
    return {name: imported_modules(path, name, known) for name, path in files.items()}


def cycles(graph: dict) -> list:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on_stack, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_the_import_graph_is_found():
    graph = import_graph()
    assert "bearing_diagnoser.diagnoser" in graph and "bearing_common.topics" in graph
    assert "bearing_common.states" in graph["bearing_common.topics"]


def test_no_import_cycles():
    assert cycles(import_graph()) == []


def test_cycle_detection_can_fail():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_packages_depend_one_way():
    """common <- sim, recordings <- observer <- diagnoser <- bringup (package level)."""
    allowed = {
        "bearing_common": set(),
        "bearing_recordings": {"bearing_common"},
        "bearing_sim": {"bearing_common"},
        # bearing_sim: only for bearing-identify --source sim
        "bearing_observer": {"bearing_common", "bearing_recordings", "bearing_sim"},
        "bearing_diagnoser": {"bearing_common", "bearing_recordings", "bearing_observer"},
        "bearing_fleet": {"bearing_common"},
        "bearing_live_view": {"bearing_common", "bearing_recordings", "bearing_diagnoser"},
        "bearing_bringup": set(PACKAGES),
    }
    for module, deps in import_graph().items():
        pkg = module.split(".")[0]
        wrong = {d for d in deps if d.split(".")[0] not in allowed[pkg] | {pkg}}
        assert not wrong, f"{module} imports {sorted(wrong)}"


TOPIC_NAMES = {t.name for t in topics.GRAPH_TOPICS.values()} | {topics.CLOCK.name, topics.FLEET_STATE.name}
TOPIC_NAMES |= {"/" + n for n in TOPIC_NAMES if not n.startswith("/")}


def literal_offences(path: pathlib.Path) -> list:
    """Topic-name string literals and QoSProfile(...) calls in ``path`` (docstrings excluded)."""
    tree = ast.parse(path.read_text(), str(path))
    docstrings = {id(n.body[0].value) for n in ast.walk(tree)
                  if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
                  and n.body and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
    # keys of data files (npz fields such as "unbalance"), not topics: dict keys, subscripts, set items
    keys = {id(k) for n in ast.walk(tree) if isinstance(n, ast.Dict) for k in n.keys if k is not None}
    keys |= {id(n.slice) for n in ast.walk(tree) if isinstance(n, ast.Subscript)}
    keys |= {id(e) for n in ast.walk(tree) if isinstance(n, ast.Set) for e in n.elts}
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings | keys:
            if node.value in TOPIC_NAMES:
                out.append(f"{path.relative_to(ROOT)}:{node.lineno}: topic name {node.value!r}")
        if isinstance(node, ast.Call):
            func = node.func
            called = func.id if isinstance(func, ast.Name) else getattr(func, "attr", "")
            if called == "QoSProfile":
                out.append(f"{path.relative_to(ROOT)}:{node.lineno}: QoSProfile(...)")
    return out


def test_topic_names_and_qos_only_in_the_contract_module():
    contract = ROOT / "src" / "bearing_common" / "bearing_common" / "topics.py"
    offences = [o for p in source_files() if p != contract and p != pathlib.Path(__file__)
                for o in literal_offences(p)]
    assert offences == []


def test_literal_check_can_fail(tmp_path):
    bad = ROOT / "tests" / "unit" / "_literal_probe.py"
    try:
        bad.write_text('from rclpy.qos import QoSProfile\nx = QoSProfile(depth=1)\nt = "fault_state"\n')
        assert len(literal_offences(bad)) == 2
    finally:
        bad.unlink()


def test_observer_and_diagnoser_import_nothing_from_the_simulator():
    for module, deps in import_graph().items():
        if module.startswith(("bearing_diagnoser", "bearing_common", "bearing_recordings")):
            assert not any(d.startswith("bearing_sim") for d in deps), module
        if module.startswith("bearing_observer") and module != "bearing_observer.identify_cli":
            assert not any(d.startswith("bearing_sim") for d in deps), module


#: Where the diagnoser may use the observer package, and what of it: the offline pipeline runs the
#: observers' sessions and picks a recording's model set with the registry's rule.
OBSERVER_USES = {"bearing_diagnoser.pipeline": {"bearing_observer.observer_session", "bearing_observer.model_sets"}}


def test_the_diagnoser_uses_the_observer_package_only_to_run_its_sessions():
    for module, deps in import_graph().items():
        if module.startswith("bearing_diagnoser"):
            used = {d for d in deps if d.split(".")[0] == "bearing_observer"}
            assert used <= OBSERVER_USES.get(module, set()), f"{module} imports {sorted(used)}"


def test_the_decision_core_and_the_front_ends_depend_one_way():
    """decision (core) <- spectral, fold (each on its own) <- front_ends, the one place naming both."""
    graph = import_graph()
    below = {"bearing_diagnoser.decision": {"bearing_diagnoser.decision"},
             "bearing_diagnoser.spectral": {"bearing_diagnoser.decision", "bearing_diagnoser.spectral"},
             "bearing_diagnoser.fold": {"bearing_diagnoser.decision", "bearing_diagnoser.fold"}}
    for module, deps in graph.items():
        for package, allowed in below.items():
            if module.startswith(package + "."):
                own = {".".join(d.split(".")[:2]) for d in deps if d.startswith("bearing_diagnoser.")}
                assert own <= allowed, f"{module} imports {sorted(own - allowed)}"
    pickers = {m for m, deps in graph.items()
               if any(d.startswith("bearing_diagnoser.spectral") for d in deps)
               and any(d.startswith("bearing_diagnoser.fold") for d in deps)}
    assert pickers <= {"bearing_diagnoser.front_ends", "bearing_diagnoser.warm_up"}, pickers


def front_end_name_comparisons(path: pathlib.Path) -> list:
    """Comparisons with the front ends' names ("spectral", "fold") in ``path``."""
    tree = ast.parse(path.read_text(), str(path))
    return [f"{path.relative_to(ROOT)}:{n.lineno}" for n in ast.walk(tree) if isinstance(n, ast.Compare)
            and any(isinstance(c, ast.Constant) and c.value in ("spectral", "fold") for c in [n.left, *n.comparators])]


def test_no_branch_on_the_front_end_outside_the_place_that_picks_it():
    package = ROOT / "src" / "bearing_diagnoser" / "bearing_diagnoser"
    assert [o for p in source_files([package]) for o in front_end_name_comparisons(p)] == []
    probe = package / "_branch_probe.py"
    try:
        probe.write_text('if config.method == "fold":\n    pass\n')
        assert len(front_end_name_comparisons(probe)) == 1
    finally:
        probe.unlink()


HIDE_SIM = """
import importlib.abc, sys
class Hide(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name == "bearing_sim" or name.startswith("bearing_sim."):
            raise ModuleNotFoundError(f"No module named {name!r} (hidden by the test)")
sys.meta_path.insert(0, Hide())
"""


def test_runs_without_bearing_sim(tmp_path):
    """With ``bearing_sim`` unimportable, the node modules import and ``bearing-diagnose`` runs."""
    import numpy as np
    rng = np.random.default_rng(0)
    path = tmp_path / "noise.npz"
    np.savez(path, accel=rng.standard_normal(48000), sample_rate=48000.0, rpm=1800.0)
    code = HIDE_SIM + (
        "import bearing_observer.node, bearing_diagnoser.node, bearing_recordings.bag_cli\n"
        "from bearing_diagnoser.diagnose_cli import main\n"
        f"sys.exit(main([{str(path)!r}]))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert '"state": "normal"' in proc.stdout, proc.stdout


def test_every_benchmark_module_imports():
    """``make bench`` imports them all: one broken import (a renamed name) lost the whole table."""
    import importlib

    from benchmarks.run import MODULES
    for name in MODULES:
        importlib.import_module(name)
