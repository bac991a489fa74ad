"""``python -m sandbox demo``: the robot anticipates a human who changes their mind.

Fits Dynamic Interaction ProMPs on synthetic diverging handovers, then streams a
new motion that starts like one task and switches to another, and prints what
the dynamic predictor believed over time next to the static baseline, and how
close each put the robot's hand to where the handover really happens.
"""

from __future__ import annotations

NAME = "demo"
HELP = "fit on synthetic diverging handovers and watch the robot anticipate an intent switch"


def add_arguments(parser) -> None:
    parser.add_argument("--seed", type=int, default=0, help="seed of the synthetic data")
    parser.add_argument("--from-task", default="up", help="task the human starts with")
    parser.add_argument("--to-task", default="right", help="task the human switches to")
    parser.add_argument("--switch", type=float, default=0.55,
                        help="when the human switches, as a fraction of the motion")
    parser.add_argument("--dow", type=float, default=0.2, help="dynamic window dow_t (s)")
    parser.add_argument("--ratio", type=float, default=0.3,
                        help="observed fraction of the static baseline")
    parser.add_argument("--demos", type=int, default=20, help="training demos per task")


def run(args) -> int:
    import numpy as np

    from sandbox.core import DynamicPredictor, IProMP, StaticPredictor
    from sandbox.data.synthetic import make_dataset
    from sandbox.data.synthetic.intent import intent_switch_demo
    from sandbox.robot import BaxterKinematics

    rng = np.random.default_rng(args.seed)
    demos = make_dataset("diverging", args.demos, rng)
    model = IProMP().fit(demos)
    for task in (args.from_task, args.to_task):
        model.task_index(task)
    test, truth = intent_switch_demo(args.from_task, args.to_task, args.switch, rng)
    times = test.times - test.times[0]
    print(f"fitted {len(model.tasks)} tasks {list(model.tasks)} on {len(demos)} synthetic demos")
    print(f"the human starts toward '{args.from_task}' and switches to '{args.to_task}' at "
          f"t = {truth.switch_time:.2f} s of {test.duration:.2f} s\n")
    dynamic = DynamicPredictor(model, dow_t=args.dow)
    static = StaticPredictor(model, ratio=args.ratio)
    print(f"{'t (s)':>6}  {'truth':>8}  {'dynamic believes':>22}  {'T est (s)':>9}  "
          f"{'jump (rad)':>10}")
    for t, y in zip(times, test.human):
        static.observe(t, y)
        upd = dynamic.observe(t, y)
        if upd is not None and (len(dynamic.updates) % max(1, round(0.2 / args.dow)) == 0):
            p = upd.task_posterior[model.task_index(upd.task)]
            print(f"{t:6.2f}  {truth.task_at(t):>8}  {upd.task:>12} (p={p:5.3f})  "
                  f"{upd.duration:9.2f}  {upd.jump:10.4f}")
    kin = BaxterKinematics()
    goal = kin.fk(test.robot[-1])
    end = times[-1]
    print()
    for name, pred in (("dynamic", dynamic), ("static", static)):
        q_end, _ = pred.command(end)
        err = float(np.linalg.norm(kin.fk(q_end) - goal))
        q_hat = np.array([pred.command(t)[0] for t in times])
        rms = float(np.sqrt(np.mean((q_hat - test.robot) ** 2)))
        print(f"{name:>8}: final task '{pred.task}', hand {100 * err:5.1f} cm from the "
              f"handover pose, joint RMS error {rms:.3f} rad, {len(pred.updates)} update(s)")
    return 0
