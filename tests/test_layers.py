"""The package's folders follow the data flow (docs/architecture.md): each layer imports only
the layers to its left, and nothing in the flow imports the commands, the production line or
the physics beside it.  A datapath's folder under hardware/ spans layers: its ``verify.py``
belongs to the verify layer and its ``analysis.py`` to the analysis layer."""

import ast
from pathlib import Path

import flann

PACKAGE = Path(flann.__file__).parent
FLOW = ("recordings", "golden", "numeric", "hardware", "eda", "verify", "implement", "analysis")
BESIDE = ("physics", "diagnose", "production", "commands", "cli")


def _layer(parts: tuple[str, ...]) -> str:
    """The layer of the module at ``parts`` (its path in the package, or its dotted name split)."""
    parts = tuple(p.removesuffix(".py") for p in parts)
    if len(parts) == 3 and parts[0] == "hardware" and parts[2] in FLOW:
        return parts[2]
    return parts[0]


def imported_layers(rel: tuple[str, ...], text: str) -> set[str]:
    """The package's top-level folders and modules the module at ``rel`` (its path in the
    package) imports."""
    found = set()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                target = list(rel[:-1])[: len(rel) - node.level] + (node.module.split(".") if node.module else [])
                target = target or [a.name for a in node.names]
            elif node.module and node.module.split(".")[0] == "flann":
                target = node.module.split(".")[1:] or [a.name for a in node.names]
            else:
                continue
            found |= {_layer(tuple(target) + (a.name,)) if len(target) == 2 else _layer(tuple(target))
                      for a in node.names}
        elif isinstance(node, ast.Import):
            found |= {_layer(tuple(a.name.split(".")[1:])) for a in node.names if a.name.startswith("flann.")}
    return found


def violations(rel: tuple[str, ...], text: str) -> list[str]:
    layer, name, out = _layer(rel), "/".join(rel), []
    for target in sorted(imported_layers(rel, text) - {layer}):
        if layer in FLOW and target in FLOW and FLOW.index(target) > FLOW.index(layer):
            out.append(f"{name}: {layer} imports {target}, which comes after it")
        elif layer in FLOW and target in BESIDE:
            out.append(f"{name}: {layer} imports {target}, which is not in the flow")
    return out


def test_every_layer_imports_only_the_layers_before_it():
    found = [v for path in sorted(PACKAGE.rglob("*.py"))
             for v in violations(path.relative_to(PACKAGE).parts, path.read_text())]
    assert found == []


def test_the_check_sees_an_upward_import():
    found = violations(("verify", "probe.py"), "from ..implement import synth\nfrom flann.commands import gen\n")
    assert found == ["verify/probe.py: verify imports commands, which is not in the flow",
                     "verify/probe.py: verify imports implement, which comes after it"]


def test_the_check_allows_a_downward_import():
    assert violations(("implement", "probe.py"), "from ..hardware.design import Design\nfrom . import timing\n") == []


def test_a_datapath_folder_spans_layers():
    assert violations(("hardware", "fixed", "verify.py"), "from ...verify.runner import sweep\nfrom .twin import FlannTop\n") == []
    assert violations(("hardware", "fixed", "datapath.py"), "from .verify import VERIFICATION\n") == [
        "hardware/fixed/datapath.py: hardware imports verify, which comes after it"]
    assert violations(("hardware", "fixed", "datapath.py"), "from . import analysis\n") == [
        "hardware/fixed/datapath.py: hardware imports analysis, which comes after it"]
