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
