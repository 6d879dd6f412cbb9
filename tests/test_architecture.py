"""Layering (ARCHITECTURE.md): imports point downward only; matplotlib only at the edges.

Checked by walking every module's AST (function-level imports included), so a violation fails here
rather than in review.
"""

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "src" / "formation_ftc"

# layer -> packages it must not import
FORBIDDEN = {
    "core": [
        "blocks",
        "design",
        "sim",
        "config",
        "papers",
        "report",
        "campaign",
        "cli",
        "api",
        "plotting",
        "methods",
        "registry",
        "league",
    ],
    "blocks": [
        "sim",
        "config",
        "papers",
        "report",
        "campaign",
        "cli",
        "api",
        "plotting",
        "methods",
        "league",
    ],
    "design": [
        "sim",
        "papers",
        "report",
        "campaign",
        "cli",
        "api",
        "plotting",
        "methods",
        "league",
    ],
    "sim": ["papers", "report", "campaign", "cli", "plotting", "methods", "league"],
    "config": ["papers", "report", "campaign", "cli", "plotting", "methods", "league"],
    "campaign": ["papers", "report", "cli", "league"],
    "components": ["papers", "report", "campaign", "cli", "api", "methods", "league"],
}
MATPLOTLIB_ALLOWED = ("plotting.py", "papers", "report", "campaign", "methods")


def _imports(path: Path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name
        elif isinstance(node, ast.ImportFrom) and node.module:
            yield node.module


@pytest.mark.parametrize("layer", sorted(FORBIDDEN))
def test_layers_import_downward_only(layer):
    bad = []
    for path in (PKG / layer).rglob("*.py"):
        for mod in _imports(path):
            for target in FORBIDDEN[layer]:
                if mod == f"formation_ftc.{target}" or mod.startswith(f"formation_ftc.{target}."):
                    bad.append(f"{path.relative_to(PKG)} imports {mod}")
    assert not bad, "\n".join(bad)


def test_matplotlib_only_at_the_edges():
    bad = []
    for path in PKG.rglob("*.py"):
        rel = path.relative_to(PKG)
        if str(rel).startswith(MATPLOTLIB_ALLOWED):
            continue
        if any(m.split(".")[0] == "matplotlib" for m in _imports(path)):
            bad.append(str(rel))
    assert not bad, bad


def test_no_eval_or_exec():
    bad = []
    for path in PKG.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Name)
                and node.func.id in {"eval", "exec"}
            ):
                bad.append(f"{path.relative_to(PKG)}:{node.lineno}")
    assert not bad, bad


def test_loading_the_plugins_imports_neither_matplotlib_nor_scipy_optimize():
    """A process that only simulates or checks (a campaign worker, ``formation-ftc check``) does not pay
    for plotting or root finding: both are imported where they are used (about 1 s of start-up)."""
    import subprocess
    import sys

    code = (
        "import sys, formation_ftc\n"
        "from formation_ftc.registry import load_plugins\n"
        "load_plugins()\n"
        "from formation_ftc import plotting\n"
        "heavy = sorted(m for m in ('matplotlib', 'scipy.optimize') if m in sys.modules)\n"
        "assert not heavy, heavy\n"
        "fig, axes = plotting.new_figure()\n"  # the first figure imports pyplot, on Agg
        "import matplotlib\n"
        "assert matplotlib.get_backend().lower() == 'agg', matplotlib.get_backend()\n"
        "assert plotting.plt is sys.modules['matplotlib.pyplot']\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
