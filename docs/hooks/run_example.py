"""Execute one jupytext percent-format example cell by cell and record what each cell printed and drew.

``python docs/hooks/run_example.py examples/NN_name.py OUT_DIR`` writes ``OUT_DIR/result.json``
(``{"cells": [{"type", "source", "stdout", "figures"}], "wall_s", "dir"}``) and one PNG per figure.
Cells share one namespace, as in a notebook; the example's folder is on ``sys.path`` (for
``_common``). A failing cell ends the process with status 1 and its traceback. The figures are taken
from matplotlib after each cell, so the example's own saving (``_common.save_figure``, which writes
``examples/figures/`` when an example runs as a script) is switched off (``FORMATION_FTC_EXAMPLES_SAVE=0``).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import sys
import time
import traceback
from pathlib import Path


def main(path: str, out_dir: str) -> int:
    import jupytext
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    src = Path(path).resolve()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    sys.path.insert(0, str(src.parent))
    sys.argv = [str(src), "--quick"]
    os.environ["FORMATION_FTC_EXAMPLES_SAVE"] = (
        "0"  # figures are captured below, not saved by the example
    )
    namespace: dict = {"__name__": "__main__", "__file__": str(src)}
    cells = []
    t0 = time.perf_counter()
    for k, cell in enumerate(jupytext.read(src).cells):
        if cell.cell_type != "code":
            cells.append({"type": "markdown", "source": cell.source, "stdout": "", "figures": []})
            continue
        buf = io.StringIO()
        try:
            with contextlib.redirect_stdout(buf):
                exec(compile(cell.source, f"{src.name} (cell {k})", "exec"), namespace)  # noqa: S102
        except Exception:  # noqa: BLE001 - reported with the cell's output
            sys.stdout.write(buf.getvalue())
            traceback.print_exc()
            return 1
        figures = []
        for j, num in enumerate(plt.get_fignums()):
            name = f"{src.stem}-{k}-{j}.png"
            plt.figure(num).savefig(out / name, dpi=90, bbox_inches="tight")
            figures.append(name)
        plt.close("all")
        cells.append(
            {"type": "code", "source": cell.source, "stdout": buf.getvalue(), "figures": figures}
        )
    result = {"cells": cells, "wall_s": time.perf_counter() - t0, "dir": str(out.resolve())}
    (out / "result.json").write_text(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
