"""The house's walls: which package may import which, and no import cycles.

The import graph is grimp's (every ``import`` in the project's modules, those inside
functions included, ``if TYPE_CHECKING:`` blocks excluded: they never run). The tests
have a wall of their own: no test module imports another (what two share is in
tests/helpers/ or conftest.py), read from their syntax trees.
"""

from __future__ import annotations

import ast
import graphlib
import sys
from pathlib import Path

import pytest

grimp = pytest.importorskip("grimp")

ROOT = Path(__file__).resolve().parents[1]

MAY_IMPORT: dict[str, set[str]] = {
    "core": set(),
    "hardware": {"core"},
    "skills": {"core", "hardware"},
    "behaviours": {"core", "hardware", "skills"},
    "trees": {"core", "hardware", "skills", "behaviours"},
    "executive": {"core", "hardware", "skills", "behaviours", "trees"},
    "evaluation": {"core", "hardware", "skills", "behaviours", "trees", "executive"},
    # The testing kit: fakes, scripted skills and fixtures for leaves and trees; nothing
    # imports it (bearchair/testing/__init__.py says why it stops below the executive).
    "testing": {"core", "hardware", "skills", "behaviours", "trees"},
}
"""Each package and the project's packages it may import: a layering, lowest first."""


@pytest.fixture(scope="module")
def graph():
    sys.path.insert(0, str(ROOT))
    try:
        return grimp.build_graph(
            "bearchair",
            include_external_packages=False,
            exclude_type_checking_imports=True,
            cache_dir=None,
        )
    finally:
        sys.path.remove(str(ROOT))


def test_every_package_of_the_distribution_has_its_place_in_the_layering():
    packages = {p.parent.name for p in ROOT.glob("*/__init__.py")} - {"tests", "bearchair"}
    assert packages == set(MAY_IMPORT)
    rooms = {p.name for p in (ROOT / "bearchair").iterdir() if (p / "__init__.py").exists()}
    assert rooms == set(MAY_IMPORT), "each room is a subpackage of bearchair"


def test_the_project_imports_its_rooms_only_under_the_one_package_name():
    # A bare ``import core`` would load a second copy of a module beside bearchair.core's.
    bare = []
    for path in sorted(ROOT.glob("*/**/*.py")):
        if path.parts[len(ROOT.parts)] in {".venv", "bearchair", "build"}:
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            words = line.split()
            if (
                len(words) >= 2
                and words[0] in {"import", "from"}
                and words[1].split(".")[0] in MAY_IMPORT
            ):
                bare.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert not bare, "imports outside bearchair:\n" + "\n".join(bare)


def room(module: str) -> str:
    """The package a module belongs to: ``bearchair.skills.x`` is in ``skills``."""
    parts = module.split(".")
    return parts[1] if parts[0] == "bearchair" and len(parts) > 1 else parts[0]


def layering_breaches(graph, may_import: dict[str, set[str]]) -> list[str]:
    """Every import from one package into another it may not import."""
    breaches = []
    for module in sorted(graph.modules):
        package = room(module)
        for imported in sorted(graph.find_modules_directly_imported_by(module)):
            other = room(imported)
            if other != package and other not in may_import[package]:
                line = graph.get_import_details(importer=module, imported=imported)[0]
                breaches.append(f"{module}:{line['line_number']} imports {imported}")
    return breaches


def import_cycle(graph) -> list[str] | None:
    """One cycle of modules importing each other, or None."""
    sorter = graphlib.TopologicalSorter(
        {module: graph.find_modules_directly_imported_by(module) for module in graph.modules}
    )
    try:
        sorter.prepare()
    except graphlib.CycleError as error:
        return list(error.args[1])
    return None


def test_each_package_imports_only_the_packages_below_it(graph):
    breaches = layering_breaches(graph, MAY_IMPORT)
    assert not breaches, "imports against the layering:\n" + "\n".join(breaches)


def test_the_mission_code_never_reaches_into_the_simulated_world(graph):
    # The skills, leaves and trees run on the real robots too: what they share with the
    # simulation (the bear's description, what counts as seated) lives outside it.
    reaching = []
    for module in sorted(graph.modules):
        if room(module) not in {"skills", "behaviours", "trees"}:
            continue
        for imported in sorted(graph.find_modules_directly_imported_by(module)):
            if imported.startswith("bearchair.hardware.sim"):
                reaching.append(f"{module} imports {imported}")
    assert not reaching, "mission code importing the simulation:\n" + "\n".join(reaching)


def test_no_module_imports_itself_through_others(graph):
    cycle = import_cycle(graph)
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_the_checks_see_a_breach_and_a_cycle(tmp_path):
    # Packages of their own names: grimp finds packages through the import system, which
    # already holds the real ``core`` and ``skills``.
    files = {
        "toy_core/m.py": "def f():\n    from toy_skills import n\n",  # in a function: counted
        "toy_skills/n.py": "from toy_skills import o\n",
        "toy_skills/o.py": "import toy_skills.n\n",
    }
    for name, body in files.items():
        path = tmp_path / name
        path.parent.mkdir(exist_ok=True)
        (path.parent / "__init__.py").write_text("")
        path.write_text(body)
    sys.path.insert(0, str(tmp_path))
    try:
        toy = grimp.build_graph(
            "toy_core", "toy_skills", include_external_packages=False, cache_dir=None
        )
    finally:
        sys.path.remove(str(tmp_path))

    assert layering_breaches(toy, {"toy_core": set(), "toy_skills": {"toy_core"}}) == [
        "toy_core.m:2 imports toy_skills.n"
    ]
    assert set(import_cycle(toy) or []) == {"toy_skills.n", "toy_skills.o"}


def imports_of_test_modules(path: Path) -> list[str]:
    """The imports in ``path`` (those inside functions too) that name a test module:
    ``tests.test_x``, ``from tests import test_x``, ``from .test_x import y``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            modules = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            # ``from tests import test_x`` and ``from . import test_x`` import modules.
            names = [alias.name for alias in node.names] if base in {"", "tests"} else []
            modules = [base, *(f"{base}.{name}" for name in names)]
        else:
            continue
        if any(part.startswith("test_") for module in modules for part in module.split(".")):
            found.append(f"{path.name}:{node.lineno}: {ast.unparse(node)}")
    return found


def test_no_test_module_imports_another():
    # What two test modules share is a helper module in tests/helpers/ (or a fixture in
    # conftest.py): a newcomer finds it there, and running one test file never collects
    # the tests of another.
    paths = sorted((ROOT / "tests").rglob("*.py")) + sorted((ROOT / "bench").glob("*.py"))
    found = [line for path in paths for line in imports_of_test_modules(path)]
    assert not found, "imports of test modules (move the helper to tests/helpers/):\n" + (
        "\n".join(found)
    )


def test_the_test_module_check_sees_every_form_of_import(tmp_path):
    path = tmp_path / "test_toy.py"
    path.write_text(
        "import tests.test_trials\n"
        "from tests.test_trials import write_chairs\n"
        "from tests import test_trials\n"
        "from . import test_trials as trials\n"
        "from .test_trials import write_chairs as chairs\n"
        "def f():\n"
        "    from tests.test_faults import FakeMission\n"
        "from tests.helpers.campaigns import write_chairs as fine\n"
        "from tests import helpers, conftest\n"
    )
    assert [line.split(":")[1] for line in imports_of_test_modules(path)] == [
        "1", "2", "3", "4", "5", "7"
    ]  # fmt: skip


MAX_MODULE_LINES = 500
"""A module longer than this holds more than one concept: split it along them."""

SHARED_BASENAMES: dict[str, str] = {
    "__init__.py": "every package has one",
    "accessibility.py": "a leaf (behaviours) and the skill it calls (skills/planning)",
    "imagine.py": "a leaf and the skill it calls (skills/imagination)",
    "scan.py": "a leaf and the skill it calls (skills/perception)",
    "seat.py": "a leaf and the skill it calls (skills/planning)",
    "walk.py": "a leaf and the skill it calls (skills/control)",
    "camera.py": "the wrist camera's backend, simulated and real (hardware/sim, hardware/real)",
    "nao.py": "the NAO's backend, simulated and real",
    "panda.py": "the Panda's backend, simulated and real, and its SDK's stand-in",
    "errors.py": "the exception tree (core) and the perception's own branch of it",
}
"""Basenames more than one module may have, each with the parallel rooms it stands for."""


def project_modules() -> list[Path]:
    """The project's module files, in the card's top-level folders."""
    return sorted(p for room in MAY_IMPORT for p in (ROOT / room).rglob("*.py"))


def test_no_module_is_longer_than_its_concept():
    long = [
        f"{path.relative_to(ROOT)}: {n} lines"
        for path in project_modules()
        if (n := len(path.read_text().splitlines())) > MAX_MODULE_LINES
    ]
    assert not long, f"modules over {MAX_MODULE_LINES} lines:\n" + "\n".join(long)


def test_two_modules_share_a_basename_only_as_parallel_rooms():
    by_name: dict[str, list[str]] = {}
    for path in project_modules():
        by_name.setdefault(path.name, []).append(str(path.relative_to(ROOT)))
    shared = {name: paths for name, paths in by_name.items() if len(paths) > 1}
    unexplained = {name: paths for name, paths in shared.items() if name not in SHARED_BASENAMES}
    assert not unexplained, f"modules sharing a basename: {unexplained}"
    stale = set(SHARED_BASENAMES) - set(shared)
    assert not stale, f"no longer shared (drop them from SHARED_BASENAMES): {sorted(stale)}"


def modules_imported_outside(paths: list[Path]) -> set[str]:
    """Every ``bearchair...`` module the files in ``paths`` import (inside functions too),
    with the modules named by ``from bearchair.x import y``."""
    found: set[str] = set()
    for path in paths:
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                found.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module:
                found.add(node.module)
                found.update(f"{node.module}.{alias.name}" for alias in node.names)
    return {name for name in found if name.startswith("bearchair")}


def entry_point_modules() -> set[str]:
    """The modules ``pyproject.toml`` names as a script or an entry point."""
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    targets = list(project.get("scripts", {}).values())
    for group in project.get("entry-points", {}).values():
        targets.extend(group.values())
    return {target.split(":")[0] for target in targets}


def test_every_module_is_used():
    # A module nothing imports is dead code, unless it is started by name: an entry
    # point, a ``python -m`` worker (it has ``if __name__``), the trial server's preload.
    # Imports under ``if TYPE_CHECKING:`` count: a package's lazy names (imported on
    # first use, by ``__getattr__``) are declared there.
    from bearchair.evaluation.forked_workers import PRELOAD_MODULE

    sys.path.insert(0, str(ROOT))
    try:
        graph = grimp.build_graph("bearchair", include_external_packages=False, cache_dir=None)
    finally:
        sys.path.remove(str(ROOT))

    outside = modules_imported_outside(
        sorted((ROOT / "tests").rglob("*.py"))
        + sorted((ROOT / "bench").glob("*.py"))
        + sorted((ROOT / "examples").rglob("*.py"))
    )
    started = entry_point_modules() | {PRELOAD_MODULE}
    unused = []
    for module in sorted(graph.modules):
        path = ROOT / Path(*module.split("."))
        if (path / "__init__.py").exists() or module in started or module in outside:
            continue
        if graph.find_modules_that_directly_import(module):
            continue
        if '__name__ == "__main__"' in (path.with_suffix(".py")).read_text():
            continue
        unused.append(module)
    assert not unused, "modules nothing imports:\n" + "\n".join(unused)
