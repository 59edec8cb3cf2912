"""How tall the import graph is: the longest import chain between the project's packages, with grimp.

Modules are grouped by package (``motion2video.X.*`` -> ``motion2video.X``; ``renderers.*`` -> ``renderers``).
Prints the height, the longest chain and any cycle (strongly connected groups), as JSON with ``--json``.

    PYTHONPATH=. python scripts/import_graph_height.py
"""

from __future__ import annotations

import argparse
import json

import grimp
import networkx as nx



def group(module: str) -> str:
    parts = module.split(".")
    if parts[0] == "renderers":
        return "renderers"
    return ".".join(parts[:2])


def measure() -> dict:
    graph = grimp.build_graph("motion2video", "renderers", include_external_packages=False)
    g = nx.DiGraph()
    for importer in graph.modules:
        for imported in graph.find_modules_directly_imported_by(importer):
            a, b = group(importer), group(imported)
            if a != b:
                g.add_edge(a, b)
    cycles = [sorted(c) for c in nx.strongly_connected_components(g) if len(c) > 1]
    dag = nx.condensation(g)
    chain = ["/".join(sorted(dag.nodes[n]["members"])) for n in nx.dag_longest_path(dag)]
    return {"height": len(chain), "longest_chain": chain, "cycles": cycles}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print JSON")
    result = measure()
    if parser.parse_args().json:
        print(json.dumps(result, indent=1))
    else:
        print(f"height {result['height']}: {' -> '.join(result['longest_chain'])}")
        print(f"cycles: {result['cycles'] or 'none'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
