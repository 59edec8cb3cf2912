"""The import-linter contracts of pyproject.toml hold on the real import graph, and each one really fails when
a forbidden import is added to that graph (an application importing another, a renderer importing a model, a
cycle, the core importing a stage)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import grimp
import pytest
from importlinter.configuration import configure
from importlinter.contracts.acyclic_siblings import AcyclicSiblingsContract
from importlinter.contracts.forbidden import ForbiddenContract
from importlinter.contracts.independence import IndependenceContract
from importlinter.contracts.layers import LayersContract

ROOT = Path(__file__).resolve().parents[1]
configure()  # import-linter's own settings (timer, caches), as lint-imports sets them
TYPES = {"layers": LayersContract, "independence": IndependenceContract, "forbidden": ForbiddenContract,
         "acyclic_siblings": AcyclicSiblingsContract}


def _contracts() -> dict[str, object]:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    session = {k: v for k, v in config.items() if k != "contracts"}
    out = {}
    for c in config["contracts"]:
        options = {k: str(v).lower() if isinstance(v, bool) else v for k, v in c.items() if k not in ("name", "type")}
        out[c["type"] + ":" + c["name"]] = TYPES[c["type"]](name=c["name"], session_options=session,
                                                          contract_options=options)
    return out


@pytest.fixture(scope="module")
def graph() -> grimp.ImportGraph:
    return grimp.build_graph("motion2video", "renderers", include_external_packages=False)


def _broken(graph: grimp.ImportGraph, importer: str | None = None, imported: str | None = None) -> set[str]:
    g = graph.copy() if hasattr(graph, "copy") else grimp.build_graph("motion2video", "renderers")
    if importer is not None:
        g.add_import(importer=importer, imported=imported, line_number=1, line_contents="import x")
    return {name.split(":")[0] for name, c in _contracts().items() if not c.check(g, verbose=False).kept}


def test_every_contract_holds_on_the_code(graph):
    assert _broken(graph) == set()


@pytest.mark.parametrize("importer, imported, contract", [
    ("motion2video.apps.sample", "motion2video.apps.transfer", "independence"),  # applications are siblings
    ("renderers.skeleton", "motion2video.models.base", "forbidden"),  # renderers import no learning code
    ("renderers.body", "motion2video.generator.model", "forbidden"),
    ("motion2video.formats.canonical", "motion2video.formats.bvh", "acyclic_siblings"),  # bvh imports canonical
    ("motion2video.core.motion", "motion2video.stages.clips", "layers"),  # the core is the bottom layer
    ("motion2video.stages.sampling", "motion2video.apps.synthesize", "layers"),  # stages sit below applications
])
def test_each_violation_breaks_its_contract(graph, importer, imported, contract):
    assert contract in _broken(graph, importer, imported)


def package_of(module: str) -> str:
    """The unit a layer is made of: ``renderers`` or the first folder (or module) under ``motion2video``."""
    parts = module.split(".")
    return parts[0] if parts[0] == "renderers" or len(parts) == 1 else ".".join(parts[:2])


def import_height(graph: grimp.ImportGraph) -> dict[str, int]:
    """Per package (:func:`package_of`): the number of packages on the longest chain of imports starting at it
    (1 for one that imports no other). A cycle between packages raises ValueError."""
    edges: dict[str, set[str]] = {}
    for module in graph.modules:
        for imported in graph.find_modules_directly_imported_by(module):
            a, b = package_of(module), package_of(imported)
            if a != b and b != "motion2video":  # the package __init__'s lazy names are not imports
                edges.setdefault(a, set()).add(b)
    heights: dict[str, int] = {}

    def height(node: str, path: tuple[str, ...]) -> int:
        if node in path:
            raise ValueError(f"import cycle: {' -> '.join(path + (node,))}")
        if node not in heights:
            heights[node] = 1 + max((height(b, path + (node,)) for b in edges.get(node, ())), default=0)
        return heights[node]

    for node in list(edges):
        height(node, ())
    return heights


def test_the_package_graph_has_no_cycle_and_at_most_seven_layers(graph):
    heights = import_height(graph)
    assert max(heights.values()) <= 7, sorted(heights.items(), key=lambda kv: -kv[1])[:3]
    assert heights["motion2video.core"] == 1 and heights["motion2video.cli"] <= 2  # the CLI loads commands lazily
    broken = grimp.build_graph("motion2video", "renderers", include_external_packages=False)
    broken.add_import(importer="motion2video.core.motion", imported="motion2video.formats.bvh", line_number=1,
                      line_contents="import x")
    with pytest.raises(ValueError, match="import cycle"):
        import_height(broken)
