"""``python -m sandbox episodes``: handover success of policies side by side, in seeded episodes.

Every policy runs the same episodes (the same seeds and, in the ``recorded``
scenario, the same held-out trials) through :func:`sandbox.episodes.scenarios.run_scenario`.
The table gives, per policy, the handover success rate with its 95 % bootstrap
interval over episodes, the fraction of episodes whose final recognised task
is the true one, the mean handover time and the median final distance.

Example: every recorded trial replayed once, leave-one-out, the dynamic and
static policies beside the recorded robot's own motion::

    python -m sandbox episodes --scenario recorded --data ../shared/data/birl-handover-20180329 \\
        --policies dynamic,static,recorded_robot --observe hand,arm,emg --episodes 174
"""

from __future__ import annotations

NAME = "episodes"
HELP = "handover success of policies side by side in seeded scenario episodes"


def add_arguments(parser) -> None:
    from sandbox.commands import _types
    from sandbox.episodes.scenarios import POLICIES, SCENARIOS

    parser.add_argument("--scenario", default="diverging", choices=sorted(SCENARIOS),
                        help="what the human does (default diverging)")
    parser.add_argument("--policies", default="dynamic,static", metavar="NAMES",
                        help=f"comma-separated, among {', '.join(POLICIES)} "
                             "(default dynamic,static)")
    parser.add_argument("--data", default=None, help="recorded set's folder (scenario recorded)")
    parser.add_argument("--observe", default=None, metavar="NAMES",
                        help="modalities the policies observe: hand, arm, emg (default: the "
                             "hand; synthetic scenarios: the model's)")
    parser.add_argument("--episodes", type=_types.integer(1, 100_000), default=20,
                        help="episodes per policy (recorded: the number of held-out trials; "
                             "the set's size replays each trial once) (default 20)")
    parser.add_argument("--seed", type=_types.SEED, default=0,
                        help="seed of episode 0 (default 0)")
    parser.add_argument("--dow", type=_types.SECONDS, default=0.2,
                        help="dynamic window dow_t (s) (default 0.2)")
    parser.add_argument("--ratio", type=_types.FRACTION, default=0.3,
                        help="static observed ratio (default 0.3)")
    parser.add_argument("--json", type=_types.output_file, default=None, metavar="FILE",
                        help="write the summaries and every episode's outcome as JSON")
    parser.add_argument("--force", action="store_true", help="overwrite an existing --json file")


def run(args) -> int:
    import json

    from sandbox.commands._observation import split
    from sandbox.episodes.scenarios import POLICIES

    policies = split(args.policies) or []
    unknown = [p for p in policies if p not in POLICIES]
    if not policies or unknown or len(set(policies)) != len(policies):
        raise ValueError(f"--policies: expected distinct names among {list(POLICIES)}, "
                         f"got {args.policies!r}")
    from sandbox.commands._outputs import check_new, write_text

    check_new([("--json", args.json)], args.force)
    out = {name: _run_policy(name, args) for name in policies}
    print(table(out))
    if args.json:
        write_text(args.json, json.dumps(out, indent=1))
    return 0


def _run_policy(name: str, args) -> dict:
    import numpy as np

    from sandbox.episodes.scenarios import run_scenario, summarize
    from sandbox.eval.metrics import bootstrap_ci

    observe = None if name == "recorded_robot" else args.observe
    results = run_scenario(args.scenario, name, n_episodes=args.episodes, seed=args.seed,
                           dow_t=args.dow, ratio=args.ratio, data=args.data, observe=observe)
    summary = summarize(results)
    success = np.array([r.success for r in results], dtype=float)
    summary["success_rate_ci"] = list(bootstrap_ci(success, rng=np.random.default_rng(0)))
    episodes = [{"seed": r.seed, "task": r.task, "final_task": r.final_task,
                 "success": r.success, "handover_time": r.handover_time,
                 "min_distance": r.min_distance, "final_distance": r.final_distance,
                 "options": r.options} for r in results]
    return {"summary": summary, "episodes": episodes}


def table(out: dict) -> str:
    """The Markdown table of :func:`run`'s results (one row per policy)."""
    lines = ["| policy | success [95 % CI] | recognised at the end | handover time (s) | "
             "final distance (m) |", "|---|---|---|---|---|"]
    for name, entry in out.items():
        s = entry["summary"]
        lo, hi = s["success_rate_ci"]
        lines.append(f"| {name} | {s['success_rate']:.2f} [{lo:.2f}, {hi:.2f}] | "
                     f"{s['recognition_rate']:.2f} | {s['handover_time_s']:.2f} | "
                     f"{s['final_distance_m']:.3f} |")
    return "\n".join(lines)
