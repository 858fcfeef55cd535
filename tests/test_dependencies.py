"""What each package may import: core only numpy/scipy/lapx/shapely, the service no figure code.

The import statements are read from the source (an AST scan, so a lazy import
inside a function counts too), and the processes that matter — importing every
``core`` module, building the served application — are run in a fresh
interpreter whose ``sys.modules`` is then inspected.
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
import tomllib
from importlib.metadata import packages_distributions, requires
from pathlib import Path

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
CORE_THIRD_PARTY = {"numpy", "scipy", "lap", "shapely"}  # lap is the lapx distribution
NEVER_AT_RUNTIME = {"matplotlib", "tqdm", "filterpy", "pyyaml"}
OUR_PACKAGES = {"app", "api_schemas", "core", "evaluation"}
PLOTTING = ("matplotlib", "tqdm", "evaluation.figures")


def imported_modules(path: Path, module_level_only: bool = False) -> set[str]:
    """The top-level names of the modules a source file imports (relative imports excluded)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    statements = tree.body if module_level_only else list(ast.walk(tree))
    names: set[str] = set()
    for statement in statements:
        if isinstance(statement, ast.Import):
            names.update(alias.name.partition(".")[0] for alias in statement.names)
        elif isinstance(statement, ast.ImportFrom) and statement.level == 0 and statement.module:
            names.add(statement.module.partition(".")[0])
    return names


def requirement_name(requirement: str) -> str:
    return canonicalize_name(Requirement(requirement).name)


def distribution_closure(names: set[str]) -> set[str]:
    """The named distributions and all they require here (no extras, markers evaluated)."""
    closure: set[str] = set()
    pending = list(names)
    while pending:
        name = pending.pop()
        if name in closure:
            continue
        closure.add(name)
        for text in requires(name) or ():
            requirement = Requirement(text)
            if requirement.marker is None or requirement.marker.evaluate({"extra": ""}):
                pending.append(canonicalize_name(requirement.name))
    return closure


def run_python(code: str) -> list[str]:
    """Run ``code`` in a fresh interpreter at the root; it prints a JSON list."""
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True
    )
    names: list[str] = json.loads(done.stdout.splitlines()[-1])
    return names


def test_core_imports_only_the_standard_library_numpy_scipy_lapx_shapely() -> None:
    allowed = set(sys.stdlib_module_names) | CORE_THIRD_PARTY | {"core"}
    for path in sorted((ROOT / "core").rglob("*.py")):
        extra = imported_modules(path) - allowed
        assert not extra, f"{path.relative_to(ROOT)} imports {sorted(extra)}"


def test_importing_all_of_core_loads_neither_the_service_nor_the_evaluation() -> None:
    loaded = run_python(
        "import json, pkgutil, importlib, sys, core\n"
        "for found in pkgutil.walk_packages(core.__path__, 'core.'):\n"
        "    importlib.import_module(found.name)\n"
        "print(json.dumps(sorted(sys.modules)))"
    )
    assert "core.fusion.engine" in loaded  # the walk did import the modules
    tops = {name.partition(".")[0] for name in loaded}
    for forbidden in ("evaluation", "app", "api_schemas", "fastapi", "pydantic", "matplotlib"):
        assert forbidden not in tops, forbidden
    assert not {"filterpy", "yaml", "tqdm"} & tops


WEB_FREE = (
    "app/errors.py",
    "app/settings.py",
    "app/inputs",
    "app/sessions",
    "app/stores",
    "app/cluster",
    "app/geo",
    "app/outputs",
)
"""The service's domain: errors, settings, input kinds, sessions, stores, cluster, geodesy
and output writers know nothing of HTTP (the edge, ``app/http`` and ``app/routes``, maps
their errors to problems)."""


def full_imports(path: Path) -> set[str]:
    """The dotted names of the modules a source file imports (every import statement)."""
    names: set[str] = set()
    for statement in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(statement, ast.Import):
            names.update(alias.name for alias in statement.names)
        elif isinstance(statement, ast.ImportFrom) and statement.level == 0 and statement.module:
            names.add(statement.module)
    return names


def test_the_domain_imports_neither_a_web_framework_nor_the_http_edge() -> None:
    paths = [ROOT / part for part in WEB_FREE]
    files = [
        file for path in paths for file in (sorted(path.rglob("*.py")) if path.is_dir() else [path])
    ]
    assert len(files) > 10
    for file in files:
        web = {
            name
            for name in full_imports(file)
            if name.partition(".")[0] in {"fastapi", "starlette"} or name.startswith("app.http")
        }
        assert not web, f"{file.relative_to(ROOT)} imports {sorted(web)}"


def test_the_service_runtime_dependencies_cover_its_imports_and_nothing_of_the_figures() -> None:
    runtime = {requirement_name(r) for r in PROJECT["dependencies"]}
    assert not runtime & NEVER_AT_RUNTIME
    assert {"matplotlib", "tqdm"} <= {
        requirement_name(r) for r in PROJECT["optional-dependencies"]["figures"]
    }
    assert {"filterpy", "pyyaml"} <= {
        requirement_name(r) for r in PROJECT["optional-dependencies"]["dev"]
    }
    installed = distribution_closure(runtime)
    distributions = packages_distributions()
    generators = {ROOT / "app" / "asyncapi.py"}  # `make openapi` only: needs the dev extra
    for package in ("app", "api_schemas", "core"):
        for path in sorted((ROOT / package).rglob("*.py")):
            if path in generators:
                continue
            for module in imported_modules(path, module_level_only=True):
                if module in sys.stdlib_module_names or module in OUR_PACKAGES:
                    continue
                owners = {requirement_name(d) for d in distributions.get(module, [])}
                assert owners & installed, f"{path.relative_to(ROOT)}: {module} ({owners})"


def test_serving_loads_no_plotting_code() -> None:
    loaded = run_python(
        "import json, sys\n"
        "from app.cli import build_parser\n"
        "from app.main import create_app\n"
        "from app.settings import Settings\n"
        "args = build_parser().parse_args(['serve', '--store', 'memory'])\n"
        "create_app(Settings(store=args.store))\n"
        "print(json.dumps(sorted(sys.modules)))"
    )
    assert "fastapi" in loaded and "app.main" in loaded
    for module in PLOTTING:
        assert module not in loaded, module


def test_the_cli_help_imports_neither_the_service_nor_the_core() -> None:
    loaded = run_python(
        "import contextlib, io, json, sys\n"
        "from app.cli import main\n"
        "with contextlib.suppress(SystemExit), contextlib.redirect_stdout(io.StringIO()):\n"
        "    main(['--help'])\n"
        "print(json.dumps(sorted(sys.modules)))"
    )
    assert "evaluation.catalogue" in loaded
    for module in ("fastapi", "uvicorn", "numpy", "core", *PLOTTING):
        assert module not in loaded, module


def test_reproduce_without_the_figures_extra_says_so_in_one_line(tmp_path: Path) -> None:
    blocked = (
        "import sys\n"
        "sys.modules['matplotlib'] = None  # as if the figures extra were not installed\n"
        "from app.cli import main\n"
        f"sys.exit(main(['reproduce', 'pedestrian', '--reduced', '--out', {str(tmp_path)!r}]))"
    )
    done = subprocess.run([sys.executable, "-c", blocked], cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 2
    assert done.stdout == ""
    [line] = done.stderr.splitlines()
    assert "figures extra" in line and "matplotlib" in line and "pip install" in line
    assert not list(tmp_path.iterdir())
