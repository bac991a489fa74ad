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

With ``--test B`` the replays are cross-session: one model (and its meeting
geometry) is fitted on all usable trials of ``--data`` A (a folder of sessions
pooled), and the trials of B (one set; its tasks among A's) are replayed with
it, the object riding at A's geometry; ``recorded_robot`` replays each B trial's
own recorded robot in that scene, so it shows how well a geometry learned on A
serves B. A ``--data`` folder of sessions ``ROOT/<session>/<task>/<trial>.csv``
without ``--test`` is replayed leave-one-session-out: each episode's trial is
drawn from all the sessions, its model fitted on all the other sessions
(:mod:`sandbox.episodes.replays`). In the recorded scenario every policy is
fitted on the ``--observe`` modalities, so all replay the same trials in the
same scene. Each policy's JSON entry then has a ``config`` (``scenario``,
``mode``: ``leave-one-out``, ``cross-session`` or ``leave-one-session-out``,
``train``, ``test`` or ``sessions``, ``observe``), each episode its ``replay``
(its trial's session, what its model was fitted on) and, leave-one-session-out,
``per_session``: each session's summary (also printed)::

    python -m sandbox episodes --scenario recorded --data early --test late \\
        --policies recorded_robot,dynamic --observe hand,arm,emg --episodes 88
"""

from __future__ import annotations

NAME = "episodes"
HELP = "handover success of policies side by side in seeded scenario episodes"


def add_arguments(parser) -> None:
    """Add the ``episodes`` command's options to ``parser``."""
    from sandbox.commands import _types
    from sandbox.episodes.scenarios import POLICIES, SCENARIOS
    from sandbox.robot.arms import ROBOTS

    parser.add_argument("--scenario", default="diverging", choices=sorted(SCENARIOS),
                        help="what the human does (default diverging)")
    parser.add_argument("--policies", default="dynamic,static", metavar="NAMES",
                        help=f"comma-separated, among {', '.join(POLICIES)} "
                             "(default dynamic,static)")
    parser.add_argument("--data", default=None, metavar="DIR",
                        help="scenario recorded: the recorded set's folder (leave-one-out), "
                             "or a folder of sessions ROOT/<session>/<task>/<trial>.csv "
                             "(leave-one-session-out), or with --test the trials to fit on")
    parser.add_argument("--test", default=None, metavar="DIR",
                        help="scenario recorded, cross-session: replay this set's trials with "
                             "one model of all of --data (the object at --data's meeting "
                             "geometry); its tasks among --data's")
    parser.add_argument("--session", type=_types.SEED, default=None, metavar="S",
                        help="scenarios diverging, objects: the motions of synthetic recording "
                             "session S (tracker frame, where the fingertip meets the object, "
                             "tempo, tail); the model is fitted on --train-session's demos and "
                             "recorded_robot replays each motion's own robot (the oracle)")
    parser.add_argument("--train-session", type=_types.SEED, default=None, metavar="A",
                        help="with --session: fit the model on synthetic session A instead "
                             "(the object rides at A's learned meeting geometry)")
    parser.add_argument("--spec", default=None, metavar="FILE",
                        help="scenario recorded: YAML/JSON file naming the time, robot and "
                             "modality columns of the recorded sets (default: the Baxter "
                             "recordings' layout); its modalities must include the hand")
    parser.add_argument("--observe", default=None, metavar="NAMES",
                        help="modalities the policies observe: hand, arm, emg (default: the "
                             "hand; synthetic scenarios: the model's); recorded: every "
                             "policy's model is fitted on them, recorded_robot's too")
    parser.add_argument("--episodes", type=_types.integer(1, 100_000), default=20,
                        help="episodes per policy (recorded: the number of trials replayed; "
                             "the size of the set replayed (--test, or all sessions) replays "
                             "each trial once) (default 20)")
    parser.add_argument("--seed", type=_types.SEED, default=0,
                        help="seed of episode 0 (default 0)")
    parser.add_argument("--dow", type=_types.SECONDS, default=0.2,
                        help="dynamic window dow_t (s) (default 0.2)")
    parser.add_argument("--ratio", type=_types.FRACTION, default=0.3,
                        help="static observed ratio (default 0.3)")
    parser.add_argument("--robot", default="baxter", choices=ROBOTS,
                        help="the arm: baxter (default), panda, ur5 or kinova; another than "
                             "Baxter follows the model's plans retargeted through its inverse "
                             "kinematics")
    parser.add_argument("--json", type=_types.output_file, default=None, metavar="FILE",
                        help="write the summaries and every episode's outcome as JSON")
    parser.add_argument("--force", action="store_true", help="overwrite an existing --json file")


def run(args) -> int:
    """Run ``python -m sandbox episodes`` with the parsed ``args``; return the exit status."""
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
    _check_data(args)
    _spec(args)                                   # refused before any episode runs
    out = {name: _run_policy(name, args) for name in policies}
    config = next(iter(out.values())).get("config")
    if config is not None:
        print(_mode_line(config))
    print(table(out))
    print(notes(args, out))
    print(robot_note(args, out))
    if any("per_session" in entry for entry in out.values()):
        print("\nby session:\n" + session_table(out))
    if args.json:
        write_text(args.json, json.dumps(out, indent=1))
    return 0


def _check_data(args) -> None:
    """``--test`` only in the recorded scenario, as one set; ``--data`` in one layout."""
    if args.train_session is not None and args.session is None:
        raise ValueError("--train-session: expected with --session (the session to replay)")
    if args.session is not None and args.scenario not in ("diverging", "objects"):
        raise ValueError(f"--session: expected with --scenario diverging or objects (synthetic "
                         f"sessions), got --scenario {args.scenario}")
    if args.test is not None and args.scenario != "recorded":
        raise ValueError(f"--test: expected with --scenario recorded (a recorded set to "
                         f"replay), got --scenario {args.scenario}")
    if args.scenario == "recorded" and args.data is not None:
        from sandbox.episodes.replays import replay_mode

        replay_mode(args.data, args.test, names=("--data", "--test"))


def _run_policy(name: str, args) -> dict:
    from sandbox.episodes.scenarios import run_scenario

    # recorded_robot too: its model (hence its trials and meeting geometry) is the others'
    results = run_scenario(args.scenario, name, n_episodes=args.episodes, seed=args.seed,
                           dow_t=args.dow, ratio=args.ratio, data=args.data, test=args.test,
                           observe=args.observe, session=args.session,
                           train_session=args.train_session, spec=_spec(args),
                           robot=args.robot)
    episodes = [{"seed": r.seed, "task": r.task, "final_task": r.final_task,
                 "success": r.success, "handover_time": r.handover_time,
                 "min_distance": r.min_distance, "final_distance": r.final_distance,
                 "outcome": r.outcome, "options": _jsonable(r.options),
                 **({"replay": r.replay} if r.replay else {})}
                for r in results]
    entry = {"summary": _summary(results), "episodes": episodes, "robot": args.robot}
    reach = [r.reach for r in results if r.reach is not None]
    if reach:
        entry["reach"] = float(min(reach))
        entry["note"] = results[0].note
    if args.scenario == "recorded":
        entry["config"] = _config(args, results)
    if entry.get("config", {}).get("mode") == "leave-one-session-out":
        sessions = dict.fromkeys(r.replay["session"] for r in results)
        entry["per_session"] = {s: _summary([r for r in results if r.replay["session"] == s])
                                for s in sorted(sessions)}
    return entry


def _spec(args):
    """The :class:`~sandbox.data.spec.DataSpec` of ``--spec`` (None without it); only with
    ``--scenario recorded``, and a robot part of Baxter's 7 joints."""
    if args.spec is None:
        return None
    if args.scenario != "recorded":
        raise ValueError(f"--spec: expected with --scenario recorded (it describes recorded "
                         f"sets), got --scenario {args.scenario}")
    from sandbox.commands._observation import check_robot
    from sandbox.data.spec import DataSpec

    spec = DataSpec.load(args.spec)
    check_robot(spec)
    return spec


def _jsonable(options: dict) -> dict:
    """Reset options for JSON: a scripted ``motion`` (a synthetic session's) as its source."""
    motion = options.get("motion")
    return options if motion is None else {**options, "motion": motion.source}


def _summary(results) -> dict:
    """:func:`~sandbox.episodes.scenarios.summarize` with the success rate's 95 % bootstrap
    interval (``success_rate_ci``)."""
    import numpy as np

    from sandbox.episodes.scenarios import summarize
    from sandbox.eval.metrics import bootstrap_ci

    summary = summarize(results)
    success = np.array([r.success for r in results], dtype=float)
    summary["success_rate_ci"] = list(bootstrap_ci(success, rng=np.random.default_rng(0)))
    return summary


def _config(args, results) -> dict:
    """A recorded run's ``config``: the scenario, the mode and what was fitted and replayed."""
    from sandbox.commands._observation import split
    from sandbox.data.sessions import find_sessions

    mode = results[0].replay["mode"]
    config = {"scenario": args.scenario, "mode": mode,
              "observe": split(args.observe) or ["hand"],
              **({"spec": str(args.spec)} if args.spec else {})}
    if mode == "leave-one-session-out":
        config["sessions"] = [p.name for p in find_sessions(args.data, "--data")]
    elif mode == "cross-session":
        config.update(train=str(args.data), test=str(args.test),
                      n_train=results[0].replay["n_train"])
    else:
        config.update(train=str(args.data), test=str(args.data))
    return config


def _mode_line(config: dict) -> str:
    """One line saying how the recorded trials were replayed."""
    if config["mode"] == "cross-session":
        return (f"cross-session: one model fitted on {config['train']} ({config['n_train']} "
                f"trials), replaying trials of {config['test']}")
    if config["mode"] == "leave-one-session-out":
        return (f"leave-one-session-out over {len(config['sessions'])} sessions: "
                f"{', '.join(config['sessions'])} (each trial with a model of the others)")
    return f"leave-one-out: each trial of {config['train']} with a model of the others"


def notes(args, out: dict) -> str:
    """What the table is over and how to read it, printed beneath it."""
    n = next(iter(out.values()))["summary"]["n_episodes"]
    if args.scenario == "recorded":
        what = f"{n:.0f} episodes per policy, each replaying one recorded trial (the same trials " \
               f"for every policy)"
    else:
        session = "" if args.session is None else f" of synthetic session {args.session}"
        what = (f"{n:.0f} episodes per policy{session}, seeds {args.seed} to "
                f"{args.seed + int(n) - 1} (the same motions for every policy)")
    lines = [f"{what}. Success: the handover happened (95 % bootstrap interval over episodes); "
             "recognised at the end: the final recognised task is the true one; handover time: "
             "the mean over the successful episodes only; final distance: the median "
             "fingertip-to-object distance at the end."]
    if "recorded_robot" in out:
        lines.append("recorded_robot is no predictor: it replays each motion's own recorded (or "
                     "synthetic) robot, so its row is the reference the others are measured "
                     "against.")
    return "\n".join(lines)


def robot_note(args, out: dict) -> str:
    """Which arm acted; for a retargeted one, the reach of the models' meeting points."""
    entry = next(iter(out.values()))
    line = f"robot: {args.robot}"
    if "reach" in entry:
        line += (f"; reaches {entry['reach']:.2f} of the model's meeting points"
                 + (f". {entry['note']}" if entry.get("note") else ""))
    unreachable = {n: sum(e["outcome"] == "unreachable" for e in v["episodes"])
                   for n, v in out.items()}
    if any(unreachable.values()):
        line += "; episodes ending 'unreachable': " + ", ".join(
            f"{n} {k}" for n, k in unreachable.items())
    return line


def table(out: dict) -> str:
    """The Markdown table of :func:`run`'s results (one row per policy)."""
    lines = ["| policy | success [95 % CI] | recognised at the end | handover time (s) | "
             "final distance (m) |", "|---|---|---|---|---|"]
    lines += [f"| {name} | {_cells(entry['summary'])} |" for name, entry in out.items()]
    return "\n".join(lines)


def session_table(out: dict) -> str:
    """The Markdown table of each policy's ``per_session`` summaries (one row per session)."""
    lines = ["| policy | session | episodes | success [95 % CI] | recognised at the end | "
             "handover time (s) | final distance (m) |", "|---|---|---|---|---|---|---|"]
    for name, entry in out.items():
        lines += [f"| {name} | {session} | {s['n_episodes']:.0f} | {_cells(s)} |"
                  for session, s in entry.get("per_session", {}).items()]
    return "\n".join(lines)


def _cells(s: dict) -> str:
    lo, hi = s["success_rate_ci"]
    return (f"{s['success_rate']:.2f} [{lo:.2f}, {hi:.2f}] | {s['recognition_rate']:.2f} | "
            f"{s['handover_time_s']:.2f} | {s['final_distance_m']:.3f}")
