"""``python -m sandbox play``: drive the human hand from the keyboard, or run a scenario file.

Without ``--scenario``: keyboard teleop (:mod:`sandbox.episodes.keyboard`). The robot,
driven by the dynamic IProMP policy, anticipates live in the browser (the URL
is printed; meshcat on localhost), and the terminal shows the hand position
and the task posterior at every update.

With ``--scenario FILE`` (JSON or YAML, see :mod:`sandbox.episodes.scenario_files`, or
the name of a shipped example: ``intent_switch``, ``waypoints``): the scripted
episode runs to completion, then its replay (HTML) and a JSON summary are
written (success, handover time, final gripper-to-object distance, recognised
task over time, updates). ``--observe hand,arm,emg`` chooses the modalities
the policy observes (and its model is fitted on) in both modes.

``--model FILE`` (saved by ``fit``) drives the robot in both modes instead of
a model fitted here (in a scenario it replaces the file's ``model:``);
``--config FILE`` (written by ``tune --out``) applies tuned settings: the
model options when the model is fitted here, ``observe`` and the predictor
options (see ``sandbox/commands/_settings.py``). A scenario's outputs are
replaced only with ``--force``. Ctrl-C ends either mode with status 130.

``--record-demos DIR --task NAME`` (teleop only) saves every episode as a
demonstration of task NAME in the recorded CSV layout, ``DIR/NAME/NNN.csv``
(:mod:`sandbox.episodes.demos_recording`), for ``fit --data DIR``; the robot holds
still at home unless ``--model`` is given.
"""

from __future__ import annotations

import sys

from sandbox.commands import _model, _outputs, _settings, _types

NAME = "play"
HELP = ("drive the human hand from the keyboard while the robot anticipates live in the "
        "browser, or run a scripted scenario file")


def add_arguments(parser) -> None:
    """Add the ``play`` command's options to ``parser``."""
    from sandbox.robot.arms import ROBOTS

    parser.add_argument("--robot", default=None, choices=ROBOTS,
                        help="the arm: baxter (default), panda, ur5 or kinova (the model's plans "
                             "retargeted); with --scenario it replaces the file's robot:")
    parser.add_argument("--scenario", metavar="FILE", default=None,
                        help="run a scenario file (.json/.yaml) or a shipped example "
                             "(intent_switch, waypoints) instead of the keyboard teleop; keys: "
                             "name, family, seed, object, speed, time_limit, observe, human "
                             "(task/switch_to/switch_phase, waypoints or recorded), policy "
                             "(type, dow_t or ratio, options), model (demos, seed, options, "
                             "file); README 'Scenario files' gives each one's meaning and "
                             "default")
    parser.add_argument("--spec", default=None, metavar="FILE",
                        help="scenario with a recorded human: the recorded set's spec file "
                             "(YAML/JSON: its time, robot and modality columns), as the file's "
                             "human.spec")
    parser.add_argument("--out", type=_types.output_file_in_new_folder, default=None,
                        help="scenario replay (HTML; default: <file name>.html here)")
    parser.add_argument("--summary", type=_types.output_file_in_new_folder, default=None,
                        help="scenario summary (JSON; default: <file name>.summary.json here)")
    parser.add_argument("--observe", default=None, metavar="NAMES",
                        help="modalities the policy observes, comma-separated: hand, arm, emg "
                             "(scenario: replaces the file's observe:; teleop: hand or hand,arm, "
                             "the model is fitted on them; default hand)")
    parser.add_argument("--family", default="diverging", choices=["diverging", "objects"],
                        help="teleop: the synthetic tasks the robot knows")
    parser.add_argument("--dow", type=_types.SECONDS, default=0.2,
                        help="teleop: dynamic window (s), in (0, 60]")
    parser.add_argument("--demos", type=_types.DEMOS, default=20,
                        help="teleop: training demos per task (at least 2)")
    parser.add_argument("--seed", type=_types.SEED, default=0,
                        help="teleop: seed of demos and episodes")
    parser.add_argument("--time-limit", type=_types.EPISODE, default=20.0,
                        help=f"teleop: episode length limit (s), in (0, {_types.MAX_EPISODE_S:g}]")
    parser.add_argument("--start", action="store_true",
                        help="teleop: start the clock at once (default: press space)")
    parser.add_argument("--open", action="store_true", help="teleop: open the browser")
    _model.add_argument(parser, "the robot uses it instead of a model fitted here (scenario: "
                                "replaces the file's model:)")
    _settings.add_argument(parser)
    _outputs.add_force(parser, "the scenario's --out and --summary files")
    parser.add_argument("--host", default="127.0.0.1", metavar="ADDRESS",
                        help="teleop: address the live viewer listens on (default 127.0.0.1, "
                             "this machine only; 0.0.0.0 lets anyone on the network watch)")
    _add_record_arguments(parser)
    _add_record_minari(parser)


# -- recording demonstrations (teleop) ------------------------------------------------------


def _add_record_arguments(parser) -> None:
    group = parser.add_argument_group("recording demonstrations (teleop)")
    group.add_argument("--record-demos", metavar="DIR", default=None,
                       help="save every teleop episode (ended by n, q, the handover or the "
                            "time limit) as a demonstration DIR/NAME/NNN.csv in the recorded "
                            "layout (hand as tracked, robot by IK to where the hand stopped), "
                            "for fit --data DIR; the robot holds still at home while you "
                            "record, unless --model is given (then it anticipates)")
    group.add_argument("--task", metavar="NAME", default=None,
                       help="with --record-demos: the task the demonstrations show "
                            "(letters, digits, _ . -)")


def _demo_recorder(args):
    """The demonstration recorder ``--record-demos``/``--task`` ask for, or None."""
    if args.record_demos is None:
        if args.task is not None:
            raise ValueError("--task: expected it with --record-demos DIR")
        return None
    if args.scenario is not None:
        raise ValueError("--record-demos: expected the keyboard teleop, got --scenario too")
    if args.task is None:
        raise ValueError("--record-demos: expected --task NAME, the task the demos show")
    from sandbox.episodes.demos_recording import DemoRecorder

    return DemoRecorder(args.record_demos, args.task)


# --record-minari (Minari extra): the played episodes as a Minari dataset ----------------
def _add_record_minari(parser) -> None:
    parser.add_argument("--record-minari", metavar="ID", default=None,
                        help="record the played episodes with minari.DataCollector as the "
                             "Minari dataset ID, e.g. sandbox/played-v0 "
                             '(pip install -e ".[minari]")')


def _recorder(args):
    """(wrap, save): wrap an env in a DataCollector, save what it recorded; no-ops without
    ``--record-minari``. The id is checked before anything is played."""
    if args.record_minari is None:
        return (lambda env: env), (lambda env, name: None)
    from sandbox.episodes.minari_export import check_new_dataset_id, collect, save_collected

    dataset_id = check_new_dataset_id(args.record_minari)

    def save(env, name: str) -> None:
        dataset = save_collected(env, dataset_id, algorithm_name=name, description=(
            f"episodes played with python -m sandbox play ({name})"))
        print(f"recorded {dataset.total_episodes} episode(s), {dataset.total_steps} steps, as the "
              f"Minari dataset {dataset_id}" if dataset else "no step played: nothing recorded",
              flush=True)

    return collect, save


def run(args) -> int:
    """Run ``python -m sandbox play`` with the parsed ``args``; return the exit status."""
    recorder = _demo_recorder(args)
    args.record = _recorder(args)
    if args.scenario is not None:
        return _scenario(args)
    if args.spec is not None:
        raise ValueError("--spec: expected with --scenario FILE whose human is recorded")
    if recorder is not None and (args.robot or "baxter") != "baxter":
        raise ValueError(f"--robot: expected baxter with --record-demos (the demos record "
                         f"Baxter's joints), got {args.robot}")
    from sandbox.validation import check_positive
    from sandbox.viz.server import check_host

    check_positive(args.dow, "--dow")
    check_positive(args.time_limit, "--time-limit")
    if args.demos < 2:
        raise ValueError(f"--demos: expected at least 2 demos per task, got {args.demos}")
    try:
        check_host(args.host)
    except ValueError as error:
        raise ValueError(f"--{error}") from None
    return _teleop(args, recorder)


def _teleop(args, recorder=None) -> int:
    import gymnasium as gym

    from sandbox.envs import ENV_IDS
    from sandbox.episodes.keyboard import Keyboard, run_teleop

    env_id = ENV_IDS[0] if args.family == "objects" else ENV_IDS[1]
    model, policy, known = _teleop_policy(args)
    policy_observe = list(getattr(policy, "observe", ()) or ["hand"])   # before any wrapper
    if recorder is not None and args.model is None:
        from sandbox.episodes.demos_recording import HeldRobot

        policy, known = HeldRobot(policy), known + "; the robot holds still while you record"
    observed = ",".join(policy_observe)
    print(f"the robot knows {len(model.tasks)} tasks {list(model.tasks)} ({known}); it "
          f"observes {observed} and re-predicts every {args.dow:g} s", flush=True)
    if not sys.stdin.isatty():
        print("stdin is not a terminal: keys are read from it as they come, and when it ends "
              "the clock runs the episode out by itself", flush=True)
    if recorder is not None:
        print(f"recording demos of task '{recorder.task}' in {recorder.folder}: each episode is "
              f"saved when it ends (n, q, handover, time limit)", flush=True)
    env = gym.make(env_id, render_mode="human",
                   max_episode_steps=max(1, round(args.time_limit * 50)),
                   viewer_options={"open_browser": args.open, "host": args.host},
                   robot=args.robot or "baxter")
    wrap, save = args.record
    env = wrap(env)
    try:   # Ctrl-C: the environment closes, the terminal is restored, cli.main says it
        with Keyboard() as keyboard:
            episodes = run_teleop(env, policy, keyboard, seed=args.seed, running=args.start,
                                  out=lambda line: print(line, flush=True), recorder=recorder)
    finally:
        try:
            save(env, "teleop + IProMPPolicy")
        finally:
            env.close()
    saved = "" if recorder is None else f", {len(recorder.saved)} demo(s) saved"
    print(f"bye ({episodes} episode(s){saved})", flush=True)
    return 0


def _teleop_policy(args):
    """The teleop's model, policy and what the robot knows, all checked before the env opens."""
    from sandbox.episodes.policies import IProMPPolicy

    settings = _settings.load(args.config)
    observe = _settings.observe(args.observe, settings)
    if args.model is not None:
        model = _model.load(args.model)
        _model.baxter(model)
        known = f"from {args.model}"
    else:
        from sandbox.episodes.scenario_runner import fit_family

        observe = observe or "hand"
        model = fit_family(args.family, args.demos, args.seed, observe,
                           _settings.model_options(settings))
        known = f"{args.demos} synthetic demos each"
    try:
        policy = IProMPPolicy(model, dow_t=args.dow, observe=observe,
                              robot=args.robot or "baxter",
                              **_settings.predictor_options(settings))
    except ValueError as error:
        raise ValueError(f"--model/--observe: {error}" if args.model else str(error)) from None
    return model, policy, known


def _scenario(args) -> int:
    import json
    from pathlib import Path

    from sandbox.episodes.scenario_files import load_scenario
    from sandbox.episodes.scenario_runner import run_scenario_file

    settings = _settings.load(args.config)
    scenario = load_scenario(args.scenario, observe=_settings.observe(args.observe, settings),
                             model=args.model,
                             options=_settings.predictor_options(settings),
                             model_options=_settings.model_options(settings), spec=args.spec,
                             robot=args.robot)
    html = Path(args.out or f"{scenario.path.stem}.html")
    summary_path = Path(args.summary or f"{scenario.path.stem}.summary.json")
    if summary_path.suffix.lower() != ".json":
        raise ValueError(f"--summary: expected a file name ending in .json, got "
                         f"{str(summary_path)!r}")
    _outputs.check_new([("--out", html), ("--summary", summary_path)], args.force)
    print(f"scenario '{scenario.name}' ({scenario.path}): {scenario.human_kind} human, "
          f"{scenario.policy['type']} policy observing {','.join(scenario.observe)}, "
          f"seed {scenario.seed}", flush=True)

    def show(belief) -> None:
        probs = " ".join(f"{k}={v:.2f}" for k, v in belief.posterior.items())
        extra = "" if belief.familiarity is None else f" familiarity={belief.familiarity:.2f}"
        if belief.familiar is False:
            extra += " UNSURE (unknown motion)"
        if belief.moving < 0.5:
            extra += f" (hand at rest: p(moving)={belief.moving:.2f})"
        print(f"  t={belief.time:5.2f}s task={belief.task} p[{probs}] T={belief.duration:.2f}s "
              f"jump={belief.jump:.4f} rad{extra}", flush=True)

    wrap, save = args.record
    summary = run_scenario_file(scenario, html=html, on_update=show,
                                wrap_env=wrap, on_close=lambda env: save(env, scenario.name))
    summary_path.parent.mkdir(parents=True, exist_ok=True)
    _outputs.write_text(summary_path, json.dumps(summary, indent=2) + "\n")
    outcome = (f"handover at {summary['handover_time_s']:.2f} s" if summary["success"]
               else f"no handover within {summary['end_time_s']:.2f} s")
    changes = ", ".join(f"{r['task']}@{r['time']:.2f}s" for r in summary["recognised"])
    print(f"{outcome}; gripper {100 * summary['final_distance_m']:.1f} cm from the object at "
          f"the end; recognised over time: {changes}")
    if summary.get("unfamiliar_updates") is not None:
        first = summary["first_warning_s"]
        print("familiarity warning: " + ("none" if first is None else
              f"from {first:.2f} s, {summary['unfamiliar_updates']} unfamiliar updates"))
    print(f"replay: {summary['replay']}\nsummary: {summary_path}")
    return 0
