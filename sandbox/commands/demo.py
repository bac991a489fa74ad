"""``python -m sandbox demo``: the robot anticipates a human who changes their mind.

Fits Dynamic Interaction ProMPs on synthetic diverging handovers, then runs an
episode of the Baxter handover environment in which the human starts toward
one task and switches to another (an intent switch). The dynamic policy
re-predicts every ``dow_t`` seconds; the static baseline, on the same motion,
predicts once after a fraction of it. Prints what each believed over time and
the outcome of both episodes, and writes the dynamic episode's replay (meshcat
scene with the predictions, a self-contained HTML file: no network needed).
``--model FILE`` uses a model saved by ``fit`` instead (it must know
``--from-task`` and ``--to-task`` and observe what the synthetic human shows:
hand, arm). An existing ``--out`` file is replaced only with ``--force``; without
``--out``, the demo replaces its own previous replay (``demo.html`` here, when it is a
replay this package wrote), so the quickstart can be run again as it is.
"""

from __future__ import annotations

from sandbox.commands import _model, _outputs, _types

NAME = "demo"
HELP = "fit on synthetic diverging handovers and watch the robot anticipate an intent switch"


def add_arguments(parser) -> None:
    """Add the ``demo`` command's options to ``parser``."""
    parser.add_argument("--out", type=_types.output_file_in_new_folder, default=None,
                        help="replay of the dynamic episode (HTML; default: demo.html here, "
                             "replacing the previous demo's replay)")
    parser.add_argument("--no-html", action="store_true", help="do not write the replay")
    parser.add_argument("--seed", type=_types.SEED, default=0,
                        help="seed of the training demos and of the episode")
    parser.add_argument("--from-task", default="up", help="task the human starts with")
    parser.add_argument("--to-task", default="right", help="task the human switches to")
    parser.add_argument("--switch", type=_types.SWITCH, default=0.55,
                        help="when the human switches, as a fraction of the motion")
    parser.add_argument("--dow", type=_types.SECONDS, default=0.2,
                        help="dynamic window dow_t (s), in (0, 60]")
    parser.add_argument("--ratio", type=_types.FRACTION, default=0.3,
                        help="observed fraction of the static baseline")
    from sandbox.robot.arms import ROBOTS

    parser.add_argument("--robot", default="baxter", choices=ROBOTS,
                        help="the arm: baxter (default), panda, ur5 or kinova (the model's plans "
                             "retargeted)")
    parser.add_argument("--demos", type=_types.DEMOS, default=20,
                        help="training demos per task (at least 2)")
    _model.add_argument(parser, "the robot uses it instead of fitting one (it must know "
                                "--from-task and --to-task)")
    _outputs.add_force(parser, "the --out replay")


DEFAULT_OUT = "demo.html"
#: The demo's model shrinks the tasks' covariances toward the pooled one
#: (:mod:`sandbox.core.shrinkage`): the diverging tasks share their first half, which
#: must leave the belief near the prior (issue 27), and their familiarity is calibrated.
SHRINKAGE = "auto"
#: How a replay written by :meth:`sandbox.viz.Viewer.save_html` begins (its title).
REPLAY_TITLE = b"<title>handover-sandbox replay</title>"


def _own_replay(path) -> bool:
    """Whether ``path`` is a replay this package wrote (its title in the first 1 KiB)."""
    try:
        with open(path, "rb") as file:
            return REPLAY_TITLE in file.read(1024)
    except OSError:
        return False


def _check(args) -> None:
    from pathlib import Path

    from sandbox.validation import check_positive

    if args.out is None:  # the default: replace our own replay, never another file
        args.out = DEFAULT_OUT
        args.force = args.force or _own_replay(Path(DEFAULT_OUT))
    if not args.no_html and Path(args.out).suffix.lower() not in (".html", ".htm"):
        raise ValueError(f"--out: expected a file name ending in .html, got {args.out!r}")
    _outputs.check_new([] if args.no_html else [("--out", args.out)], args.force)
    if args.from_task == args.to_task:
        raise ValueError(f"--to-task: expected a task other than --from-task, got "
                         f"{args.to_task!r} twice")
    if not 0.0 < args.switch < 1.0:
        raise ValueError(f"--switch: expected a fraction in (0, 1), got {args.switch}")
    if args.demos < 2:
        raise ValueError(f"--demos: expected at least 2 demos per task, got {args.demos}")
    check_positive(args.dow, "--dow")
    if not 0.0 < args.ratio <= 1.0:
        raise ValueError(f"--ratio: expected a fraction in (0, 1], got {args.ratio}")


def _belief(record, t: float) -> str:
    """'task (p=..)' the policy held at time ``t`` (the prior before its first update)."""
    done = [b for b in record.updates if b.time <= t + 1e-9]
    if not done:
        return "prior mixture"
    last = done[-1]
    return f"{last.task} (p={last.posterior[last.task]:.2f})"


def _table(dynamic, static, switch_time: float) -> None:
    print(f"{'t (s)':>6}  {'human does':>10}  {'dynamic believes':>18}  {'T est (s)':>9}  "
          f"{'jump (rad)':>10}  {'static believes':>18}")
    truth = dict(dynamic.truth)
    first_after = next((i for i, b in enumerate(dynamic.updates) if b.time >= switch_time), None)
    for i, b in enumerate(dynamic.updates):
        does = truth.get(min(truth, key=lambda t: abs(t - b.time))) if truth else "?"
        mark = "  <- the human switched" if i == first_after else ""
        believed = f"{b.task} (p={b.posterior[b.task]:.2f})"
        print(f"{b.time:6.2f}  {does:>10}  {believed:>18}  {b.duration:9.2f}  {b.jump:10.4f}  "
              f"{_belief(static, b.time):>18}{mark}")


def _outcome(name: str, record, true_task: str) -> str:
    if record.success:
        end = f"handover at {record.handover_time:.2f} s"
    else:
        end = f"no handover within {record.end_time:.1f} s"
    first = next((t for t, k in record.recognised if k == true_task), None)
    settled = _settled(record, true_task)
    recog = (f"recognised '{true_task}' from {settled:.2f} s" if settled is not None else
             f"never settled on '{true_task}'" if first is None else
             f"'{true_task}' only briefly (first at {first:.2f} s)")
    jumps = max((b.jump for b in record.updates), default=0.0)
    return (f"{name:>8}: {end}; gripper {100 * record.final_distance:4.1f} cm from the object "
            f"at the end; final task '{record.recognised[-1][1]}', {recog}; "
            f"{len(record.updates)} update(s), largest command jump {jumps:.3f} rad")


def _settled(record, task: str) -> float | None:
    """Earliest time from which the recognised task stays ``task`` to the end."""
    out = None
    for t, k in record.recognised:
        if k != task:
            out = None
        elif out is None:
            out = t
    return out


def _model_of(args):
    """The saved model of ``--model`` (checked against the episode), or one fitted here."""
    if args.model is None:
        from sandbox.data.synthetic.families import DIRECTIONS
        from sandbox.episodes.policies import fit_family_model

        unknown = [t for t in (args.from_task, args.to_task) if t not in DIRECTIONS]
        if unknown:  # checked before the fit and calibration (seconds), not after
            raise ValueError(f"--from-task/--to-task: expected tasks of the diverging family "
                             f"{list(DIRECTIONS)}, got {unknown}")
        model = fit_family_model("diverging", n_per_task=args.demos, seed=args.seed,
                                 calibrated=True, shrinkage=SHRINKAGE)
    else:
        from sandbox.episodes.scenario_files import SYNTHETIC_MODALITIES

        model = _model.load(args.model)
        _model.within(model, SYNTHETIC_MODALITIES, "the synthetic human")
        _model.baxter(model)
    _model.tasks(model, [args.from_task, args.to_task], "--from-task/--to-task")
    return model


def run(args) -> int:
    """Run ``python -m sandbox demo`` with the parsed ``args``; return the exit status."""
    _check(args)
    import time
    from pathlib import Path

    import gymnasium as gym
    import numpy as np

    import sandbox.envs  # noqa: F401  (registers the environments)
    from sandbox.episodes.policies import IProMPPolicy, StaticPolicy
    from sandbox.episodes.recording import record_episode

    start = time.perf_counter()
    model = _model_of(args)
    if args.model is None:
        print(f"fitted {len(model.tasks)} tasks {list(model.tasks)} on "
              f"{args.demos * len(model.tasks)} synthetic demos "
              f"({time.perf_counter() - start:.1f} s)")
    else:
        print(f"model {args.model}: {len(model.tasks)} tasks {list(model.tasks)}, observing "
              f"{','.join(model.modality_names)}")
    env = gym.make("sandbox/BaxterHandoverDiverging-v1", robot=args.robot)
    options = {"task": args.from_task, "switch_to": args.to_task, "switch_phase": args.switch}
    viewer = overlay = None
    try:
        if not args.no_html:
            from sandbox.viz import Viewer

            viewer = Viewer(fps=30.0)
            viewer.add_simulation(env.unwrapped.sim)
            overlay = viewer.add_overlay(
                model.tasks, rng=np.random.default_rng(args.seed),
                title=f"demo: {args.from_task} -> {args.to_task}, dynamic (dow_t={args.dow:g} s)")
        dynamic = record_episode(env, IProMPPolicy(model, dow_t=args.dow, robot=args.robot),
                                 seed=args.seed, options=options, viewer=viewer, overlay=overlay,
                                 policy_name=f"dynamic (dow_t={args.dow:g} s)")
        truth = env.unwrapped.motion.meta["intent"]
        duration = env.unwrapped.motion.duration
        static = record_episode(env, StaticPolicy(model, ratio=args.ratio, robot=args.robot),
                                seed=args.seed,
                                options=options, policy_name=f"static (ratio={args.ratio:g})")
    finally:
        env.close()
    print(f"episode (seed {args.seed}): the human starts toward '{args.from_task}' and "
          f"switches to '{args.to_task}' at t = {truth.switch_time:.2f} s of a "
          f"{duration:.2f} s reach; the robot sees the hand through the tracker\n")
    _table(dynamic, static, truth.switch_time)
    print()
    print(f"dynamic: re-predicts every {args.dow:g} s; static: predicts once after "
          f"{100 * args.ratio:.0f} % of the expected duration")
    for name, record in (("dynamic", dynamic), ("static", static)):
        print(_outcome(name, record, args.to_task))
    if viewer is not None:
        path = viewer.save_html(Path(args.out))
        size = path.stat().st_size / 1e6
        print(f"\nreplay of the dynamic episode: {path} ({size:.1f} MB; open it in a browser, "
              "drag to orbit, the animation controls are in the menu)")
    print(f"wall time {time.perf_counter() - start:.1f} s")
    return 0
