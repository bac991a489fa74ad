r"""The human's tracked arm: a shoulder on a leaning, swaying trunk, an elbow from two-link IK.

Frame and sides
---------------
Everything is in Baxter's base frame (m): x points from the robot toward the
human, y to the robot's left, z up. The human stands in front of Baxter
(shoulders at x ~ 1.2-1.35 m) facing it, i.e. facing -x. The tracker (OpenNI)
labels the skeleton mirror-wise: its *left* arm, the ``human_left_*`` columns
of :data:`~sandbox.data.spec.ARM`, is on the **+y** side of the body (the
recorded left shoulder is at y ~ 0.0 m, the right one at y ~ -0.18 m; it is the
human's anatomical right arm, which hands over to Baxter's left arm). So
*outward*, away from the body's midline, is :math:`\hat o = +y` and *forward*
(toward the robot) is :math:`\hat f = \hat z \times \hat o = -x`.

The model (one random draw per demonstration, :func:`draw_arm`)
----------------------------------------------------------------
1. **Body.** Height :math:`H` ~ N(1.70, 0.07) m, clipped to [1.50, 1.95] m;
   upper arm :math:`a = 0.186 H` (shoulder-elbow), forearm :math:`b = 0.146 H`
   (elbow-wrist), shoulder breadth :math:`B = 0.259 H` (Winter 2009, Fig. 4.1).
   The tracked hand point is taken to be the wrist: the recorded elbow-hand
   distance (median 0.241 m) is the forearm of a 1.65 m person, while a
   palm-centre point (~0.4 of the hand's 0.108 H further) would be ~7 cm
   further out.
2. **Trunk.** The mid-shoulder point :math:`M` leans toward the handover as
   the hand reaches, the trunk turns (yaw :math:`\psi`) so that the reaching
   shoulder comes forward, and it sways a little (one slow sinusoid per axis,
   :math:`\|\mathrm{sway}(t)\| \le` ``sway_m`` at all times):

   .. math::

       M(t) = M_0 + p(t - \tau)\,\lambda\,(\hat h - \delta\,\hat z) + \mathrm{sway}(t),
       \qquad \psi(t) = p(t - \tau)\,\psi_1,

       S(t) = M(t) + \tfrac{B}{2}\,(\cos\psi(t)\,\hat o + \sin\psi(t)\,\hat f),

   with :math:`p \in [0, 1]` the hand's progress along its start-end line
   (:func:`reach_progress`), :math:`\tau` a small lag, :math:`\hat h` the
   horizontal direction from the start shoulder to the hand's end,
   :math:`\lambda` the lean, :math:`\delta` its downward share and
   :math:`\psi_1` the final yaw. :math:`M_0` is placed so that the start
   shoulder :math:`S(0)` is where the recordings' is (measured mean and
   spread, up to the sway), whatever :math:`H`.
3. **Elbow.** Two-link inverse kinematics from the shoulder to the wrist
   (:mod:`sandbox.data.synthetic.two_link`) with the swivel angle
   :math:`\varphi(t) = \varphi_0 - \Delta\varphi\,p(t)^4`: the elbow is well
   outward during the reach and drops as the arm extends at its end.

Measured on the recorded set (``birl-handover-20180329``, 174 trials): the start
shoulder is at (1.348, 0.003, 0.341) m, per-axis spreads (0.015, 0.012, 0.015) m
(pooled; less within a task); from start to end it moves (-0.115, +0.020,
-0.033) m on average (median distance 0.13 m), ~0.07 s behind the hand, while
the other shoulder moves 1 cm forward and 7 cm to +y (the trunk leans and
turns); the swivel angle of the tracked skeleton is ~70-77 deg during the
reach and ~50 deg at its end. The elbow-hand distance is 0.241 m (median), the
tracked shoulder-elbow distance 0.25 m, shorter than an anatomical upper arm.

References
----------
D. A. Winter, *Biomechanics and Motor Control of Human Movement*, 4th ed.,
Wiley, 2009, Fig. 4.1 (segment lengths as fractions of body height H, after
R. Drillis and R. Contini, *Body Segment Parameters*, Tech. Rep. 1166-03,
New York University, 1966).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sandbox.data.synthetic.two_link import UP, check_outward, elbow_positions
from sandbox.validation import FloatArray, check_array, check_positive, check_rng, check_times

#: Winter (2009), Fig. 4.1: segment lengths as fractions of body height.
UPPER_ARM, FOREARM, SHOULDER_BREADTH = 0.186, 0.146, 0.259
#: Mean start of the tracked (``human_left``) shoulder in the recordings (m).
SHOULDER_START = (1.348, 0.003, 0.341)


def _check_spread(value: tuple[float, float], name: str) -> None:
    """A (mean, standard deviation) pair: finite, std >= 0."""
    if len(value) != 2 or not np.isfinite(value).all():
        raise ValueError(f"{name}: expected (mean, std), got {value!r}")
    check_positive(value[1], f"{name} std", allow_zero=True)


@dataclass(frozen=True)
class ArmModel:
    """How the tracked arm is built and how it varies between demonstrations.

    Parameters
    ----------
    height : tuple of float
        Mean and standard deviation (m) of the subject's height ``H``.
    height_range : tuple of float
        Clip of ``H`` (m).
    upper_arm, forearm, shoulder_breadth : float
        Segment lengths as fractions of ``H`` (Winter 2009, Fig. 4.1).
    shoulder_start : tuple of float
        Mean start of the tracked shoulder (m), Baxter's base frame.
    shoulder_std : tuple of float
        Per-axis standard deviations (m) of that start.
    lean : tuple of float
        Mean and standard deviation (m) of the trunk's lean toward the handover.
    drop : float
        Downward share of the lean (m down per m of horizontal lean).
    yaw_deg : tuple of float
        Mean and standard deviation (deg) of the trunk's turn that brings the
        reaching shoulder forward.
    swivel_deg : tuple of float
        Mean and standard deviation (deg) of the elbow's swivel angle during
        the reach (0: the elbow hangs straight down, > 0: outward).
    swivel_drop_deg : tuple of float
        Mean and standard deviation (deg) of its decrease by the end of the
        reach (the elbow drops as the arm extends).
    sway_m : float
        Bound (m) of the trunk's sway (0: none).
    sway_hz : tuple of float
        Range (uniform) of the sway's frequencies (Hz).
    lag_s : float
        Delay (s) of the trunk's motion behind the hand's.
    outward : tuple of float
        Horizontal unit vector from the body's midline toward the tracked shoulder.
    """

    height: tuple[float, float] = (1.70, 0.07)
    height_range: tuple[float, float] = (1.50, 1.95)
    upper_arm: float = UPPER_ARM
    forearm: float = FOREARM
    shoulder_breadth: float = SHOULDER_BREADTH
    shoulder_start: tuple[float, float, float] = SHOULDER_START
    shoulder_std: tuple[float, float, float] = (0.010, 0.008, 0.010)
    lean: tuple[float, float] = (0.07, 0.025)
    drop: float = 0.5
    yaw_deg: tuple[float, float] = (15.0, 5.0)
    swivel_deg: tuple[float, float] = (72.0, 10.0)
    swivel_drop_deg: tuple[float, float] = (25.0, 20.0)
    sway_m: float = 0.01
    sway_hz: tuple[float, float] = (0.2, 0.6)
    lag_s: float = 0.07
    outward: tuple[float, float, float] = (0.0, 1.0, 0.0)

    def __post_init__(self) -> None:
        for key in ("height", "lean", "yaw_deg", "swivel_deg", "swivel_drop_deg"):
            _check_spread(getattr(self, key), key)
        for key in ("shoulder_start", "shoulder_std"):
            if np.shape(getattr(self, key)) != (3,) or not np.isfinite(getattr(self, key)).all():
                raise ValueError(f"{key}: expected 3 numbers (m), got {getattr(self, key)!r}")
        for key in ("upper_arm", "forearm", "shoulder_breadth", "height_range", "sway_hz"):
            for value in np.atleast_1d(getattr(self, key)):
                check_positive(value, key)
        for key in ("height_range", "sway_hz"):
            if getattr(self, key)[0] > getattr(self, key)[1]:
                raise ValueError(f"{key}: expected low <= high, got {getattr(self, key)!r}")
        for key in ("drop", "sway_m", "lag_s", "shoulder_std"):
            for value in np.atleast_1d(getattr(self, key)):
                check_positive(value, key, allow_zero=True)
        check_outward(self.outward)

    @classmethod
    def still(cls) -> ArmModel:
        """A trunk that neither leans, turns nor sways (the shoulder stays at its start)."""
        return cls(lean=(0.0, 0.0), yaw_deg=(0.0, 0.0), sway_m=0.0)


@dataclass(frozen=True)
class ArmDraw:
    """One demonstration's arm: sizes and placement (m), trunk motion and swivel (rad).

    Attributes
    ----------
    height, upper_arm, forearm, half_breadth : float
        Height ``H`` and the lengths ``a``, ``b`` and ``B / 2`` (m).
    shoulder : ndarray, shape (3,)
        Start of the shoulder (m).
    lean, yaw : float
        Lean (m) and final trunk yaw (rad).
    swivel, swivel_drop : float
        Swivel angle during the reach and its decrease by the end (rad).
    sway_amp, sway_hz, sway_phase : ndarray, shape (3,)
        Per-axis amplitude (m), frequency (Hz) and phase (rad) of the sway.
    """

    height: float
    upper_arm: float
    forearm: float
    half_breadth: float
    shoulder: FloatArray
    lean: float
    yaw: float
    swivel: float
    swivel_drop: float
    sway_amp: FloatArray
    sway_hz: FloatArray
    sway_phase: FloatArray


def draw_arm(model: ArmModel, rng: np.random.Generator) -> ArmDraw:
    """Draw one demonstration's arm (see :class:`ArmModel`)."""
    H = float(np.clip(rng.normal(*model.height), *model.height_range))
    weights = np.array([1.0, 1.0, 0.3])  # the trunk sways more horizontally than vertically
    return ArmDraw(
        height=H,
        upper_arm=model.upper_arm * H,
        forearm=model.forearm * H,
        half_breadth=0.5 * model.shoulder_breadth * H,
        shoulder=np.asarray(model.shoulder_start) + rng.normal(0.0, model.shoulder_std),
        lean=max(0.0, rng.normal(*model.lean)),
        yaw=np.radians(rng.normal(*model.yaw_deg)),
        swivel=np.radians(rng.normal(*model.swivel_deg)),
        swivel_drop=np.radians(rng.normal(*model.swivel_drop_deg)),
        sway_amp=model.sway_m * rng.uniform(0.5, 1.0) * weights / np.linalg.norm(weights),
        sway_hz=rng.uniform(*model.sway_hz, 3),
        sway_phase=rng.uniform(0.0, 2.0 * np.pi, 3),
    )


def torso_sway(times: FloatArray, draw: ArmDraw) -> FloatArray:
    """The trunk's sway (m) at ``times`` (s), shape (T, 3); its norm is at most ``|sway_amp|``."""
    t = np.asarray(times, dtype=float)[:, None] - float(np.asarray(times)[0])
    return draw.sway_amp * np.sin(2.0 * np.pi * draw.sway_hz * t + draw.sway_phase)


def reach_progress(times: FloatArray, hand: FloatArray, lag_s: float = 0.0) -> FloatArray:
    """The hand's progress along its start-end line, in [0, 1], ``lag_s`` seconds late, (T,).

    Parameters
    ----------
    times : ndarray, shape (T,)
        Sample times (s), increasing.
    hand : ndarray, shape (T, 3)
        Hand positions (m).
    lag_s : float
        Delay (s): the value at ``t`` is the progress at ``t - lag_s``.
    """
    line = hand[-1] - hand[0]
    if line @ line < 1e-12:
        return np.zeros(len(times))
    p = np.clip((hand - hand[0]) @ line / (line @ line), 0.0, 1.0)
    return np.interp(np.asarray(times) - lag_s, times, p) if lag_s else p


def shoulder_positions(
    times: FloatArray, hand: FloatArray, draw: ArmDraw, model: ArmModel
) -> FloatArray:
    """Shoulder positions (m) of a trunk that leans, turns and sways, shape (T, 3).

    Parameters
    ----------
    times : ndarray, shape (T,)
        Sample times (s).
    hand : ndarray, shape (T, 3)
        Clean hand positions (m); their progress drives the lean and the turn.
    draw : ArmDraw
        The demonstration's arm.
    model : ArmModel
        Supplies ``drop``, ``lag_s`` and ``outward``.
    """
    out = np.asarray(model.outward, dtype=float)
    forward = np.cross(UP, out)
    toward = (hand[-1] - draw.shoulder) * np.array([1.0, 1.0, 0.0])
    horizontal = toward / max(np.linalg.norm(toward), 1e-12)
    p = reach_progress(times, hand, model.lag_s)[:, None]
    mid = draw.shoulder - draw.half_breadth * out + torso_sway(times, draw)
    mid = mid + p * draw.lean * (horizontal - model.drop * UP)
    psi = p * draw.yaw
    return mid + draw.half_breadth * (np.cos(psi) * out + np.sin(psi) * forward)


def arm_positions(
    times: FloatArray, hand: FloatArray, rng: np.random.Generator,
    *, model: ArmModel | None = None,
) -> FloatArray:
    """The clean (untracked) arm that goes with a clean hand path.

    Parameters
    ----------
    times : array_like, shape (T,)
        Sample times (s), strictly increasing.
    hand : array_like, shape (T, 3)
        Clean hand (wrist) positions (m), Baxter's base frame; the reach
        goes from its first row to its last.
    rng : numpy.random.Generator
        Source of the demonstration's arm draw (:func:`draw_arm`).
    model : ArmModel, optional
        Default ``ArmModel()`` (measured on the recordings).

    Returns
    -------
    ndarray, shape (T, 6)
        Elbow x, y, z then shoulder x, y, z (m): the columns of
        :data:`sandbox.data.spec.ARM`.
    """
    model = ArmModel() if model is None else model
    if not isinstance(model, ArmModel):
        raise ValueError(f"model: expected an ArmModel, got {type(model).__name__}")
    times = check_times(times, "times")
    hand = check_array(hand, "hand", 2, shape=(times.size, 3))
    draw = draw_arm(model, check_rng(rng))
    shoulder = shoulder_positions(times, hand, draw, model)
    swivel = draw.swivel - draw.swivel_drop * reach_progress(times, hand) ** 4
    elbow = elbow_positions(shoulder, hand, draw.upper_arm, draw.forearm, swivel,
                            outward=model.outward)
    return np.column_stack([elbow, shoulder])


def arm_rng(seed: int) -> np.random.Generator:
    """The arm's generator of a demonstration whose tracker is seeded with ``seed``.

    A child of ``SeedSequence(seed)`` (the tracker's own stream), so drawing
    the arm never changes the hand's or any other random number.
    """
    return np.random.default_rng(np.random.SeedSequence(int(seed)).spawn(1)[0])
