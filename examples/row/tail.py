"""The row action of workflow.toml: for every finished point of an irtp
`fp stationary` sweep, the probability in the outer tenth of the velocity
interval, from the point's density table, written to tail.json (the
action's product). Points without result.json (not finished) are left for
a later submission."""

import csv
import json
import pathlib
import sys


def tail_mass(point: pathlib.Path) -> float:
    rows = list(csv.DictReader(open(point / "density.csv")))
    edge = 0.9 * max(abs(float(r["v"])) for r in rows)
    return sum(float(r["p"]) * float(r["dv"]) for r in rows if abs(float(r["v"])) >= edge)


for name in sys.argv[1:]:
    point = pathlib.Path("workspace") / name
    if not (point / "result.json").exists():
        continue
    (point / "tail.json").write_text(json.dumps({"tail_mass": tail_mass(point)}))
