"""Update benchmarks beyond the reference case: many tasks and many demos (issue 25).

* ``update_20_tasks_ms``: the reference update (:mod:`sandbox.bench.core`: 2 s of a
  held-out hand motion, 40 kept observations, at least 50 speed candidates per task)
  with 20 tasks of 20 demos each. The synthetic diverging set has 5 tasks; each is
  made 4 tasks by shifting the hand (4 cm steps along the table) and the robot's joints
  (0.05 rad steps) of a quarter of its demos (:func:`many_tasks_case`); the shifts make
  them different tasks to the model, which is all the timing needs.
* ``update_demos_ms``: one update with 10, 20, 40, 80 and 160 training demos per task
  (4 tasks, the first 1 s of a held-out hand motion, 20 kept observations, at least 50
  candidates per task), and ``demos_160_vs_20``, the ratio of the last to the 20-demo
  update. Each task's weight covariance is a factor of rank (demos - 1) over the
  human's N x P weights, so the likelihood's matrices grow with the demos until
  that rank reaches N x P (:mod:`sandbox.core.likelihood`).

Every figure is a median over ``repeats`` updates of one predictor fed as the online
predictor is, as ``update_ms`` of :mod:`sandbox.bench.core`.
"""

from __future__ import annotations

import numpy as np

from sandbox.bench.core import TASKS, _fed_predictor, _median_ms, _timed_update

#: Training demos per task of the many-demos case.
DEMOS = (10, 20, 40, 80, 160)


def many_tasks_case(n_tasks: int = 20, n_per_task: int = 20, seed: int = 0):
    """A fitted model of ``n_tasks`` tasks, and 2 s of a held-out motion (times, human)."""
    from sandbox.core import IProMP
    from sandbox.data.synthetic import make_dataset

    rng = np.random.default_rng(seed)
    variants = -(-n_tasks // 5)
    demos = make_dataset("diverging", variants * n_per_task + 1, rng)
    train, test = [], None
    for base in sorted({d.task for d in demos}):
        items = [d for d in demos if d.task == base]
        for j in range(variants):
            if len({d.task for d in train}) == n_tasks:
                break
            shift = np.array([0.0, 0.04 * j, 0.0])
            part = items[j * n_per_task:(j + 1) * n_per_task]
            train += [d.replace(human=d.human + shift, robot=d.robot + 0.05 * j,
                                task=f"{base}{j}") for d in part]
        if test is None:
            test = items[-1]
    model = IProMP(n_basis=31).fit(train)
    t = test.times - test.times[0]
    keep = t < 2.0 - 1e-9
    return model, t[keep], test.human[keep]


def many_demos_case(n_per_task: int, seed: int = 0, span: float = 1.0):
    """A fitted 4-task model of ``n_per_task`` demos each, and ``span`` s of a held-out motion."""
    from sandbox.core import IProMP
    from sandbox.data.synthetic import make_dataset

    rng = np.random.default_rng(seed)
    demos = [d for d in make_dataset("diverging", n_per_task + 3, rng) if d.task in TASKS]
    train = [d for task in TASKS for d in [x for x in demos if x.task == task][:n_per_task]]
    test = next(d for d in demos if d.task == TASKS[0] and d not in train and d.duration > 2.2)
    model = IProMP(n_basis=31).fit(train)
    t = test.times - test.times[0]
    keep = t < span - 1e-9
    return model, t[keep], test.human[keep]


def _update_ms(model, times, values, repeats: int, n_candidates: int = 50) -> tuple[float, dict]:
    pred = _fed_predictor(model, times, values, n_candidates=n_candidates)
    t = float(pred.observations()[0][-1])
    ms = _median_ms(_timed_update(pred, t), repeats)
    spans = pred._lattice.spans()
    return ms, {"tasks": len(model.tasks), "observations": int(pred.observations()[0].size),
                "rank": int(pred.scorer.R), "pairs": int((spans[:, 1] - spans[:, 0]).sum())}


def run_case_benchmarks(repeats: int = 200, seed: int = 0) -> dict:
    """The 20-task and many-demos figures (module docstring) in one dict."""
    ms20, config20 = _update_ms(*many_tasks_case(20, seed=seed), repeats)
    demos, configs = {}, {}
    for n in DEMOS:
        ms, config = _update_ms(*many_demos_case(n, seed), max(repeats // 4, 1))
        demos[str(n)], configs[str(n)] = round(ms, 4), config
    return {"update_20_tasks_ms": round(ms20, 4), "tasks_20_config": config20,
            "update_demos_ms": demos, "demos_160_vs_20": round(demos["160"] / demos["20"], 2),
            "demos_config": configs}
