"""Builders of the docs site's generated parts: the task gallery, the diagrams, the performance
charts and their data, the learning curves, the MkDocs hook that runs them, and page
screenshots."""

from tools import ROOT

#: The benchmark tables the performance page draws (written by `tools.docs.benchmark_results`).
RESULTS = ROOT / "docs" / "data" / "benchmark_results.json"
