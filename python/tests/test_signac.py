"""A sweep directory opens as a signac project: ``signac.get_project(DIR)``
(the real package) finds every point as a job by its statepoint, the job id
is signac's own hash of it (``project.check()`` verifies every one), and
``job.doc`` holds the point's result as ``result.json`` records it."""

from __future__ import annotations

import json

import pytest

signac = pytest.importorskip("signac")

PLAN = """\
command = "fp stationary"

[fixed]
drag = "tan"
cells = 200

[axes]
sigma = [1.0, 2.5]
rate = { from = 0.1, to = 10.0, points = 3, spacing = "log" }

[[zip]]
lambda = [0.5, 5.0]
reset_velocity = [0.0, 0.1]
"""


def test_a_sweep_is_a_signac_project(cli, tmp_path):
    plan = tmp_path / "plan.toml"
    plan.write_text(PLAN)
    out = tmp_path / "sweep"
    cli.run(["sweep", "run", str(plan), "--out", str(out)])
    project = signac.get_project(str(out))
    assert len(project) == 12
    project.check()  # every job id is signac's calc_id of its statepoint
    jobs = list(project.find_jobs({"parameters.sigma": 2.5, "parameters.lambda": 5.0}))
    assert len(jobs) == 3
    for job in jobs:
        assert job.id == signac.job.calc_id(job.statepoint())
        result = json.loads((out / "workspace" / job.id / "result.json").read_text())
        assert job.doc["status"] == "ok"
        assert job.doc["summary"] == json.loads(json.dumps(result["summary"]))
        assert job.sp.parameters.reset_velocity == 0.1
    # A signac workflow may write to job.doc without damaging the point.
    jobs[0].doc["note"] = "seen"
    status = cli.run(["sweep", "status", str(out)])
    assert "complete" in status.stdout
