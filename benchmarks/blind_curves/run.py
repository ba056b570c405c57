"""The diagnosis on the third blind force-curve set (docs/diagnose.md 9.30), scored against its key.

Usage: ``python benchmarks/blind_curves/gen.py OUT_DIR`` (the 32 cases and ``KEY.json``, fixed seed), then
``python benchmarks/blind_curves/run.py OUT_DIR [RESULTS.json]``: the generic blind runner
(``benchmarks/blind_run.py``, which scores every blind set the same way) on this set.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from blind_run import main  # noqa: E402

if __name__ == "__main__":
    d = Path(sys.argv[1])
    print(json.dumps(main(d, Path(sys.argv[2]) if len(sys.argv) > 2 else d / "results.json"), indent=1))
