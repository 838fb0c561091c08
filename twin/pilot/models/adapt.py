"""A pilot who adapts: its equalisation and neuromuscular tuning chosen per motion system.

Chapter 6's pilots changed their control behaviour with the motion system (§6.4.2): behind the
1 Hz platform filter the motion gain fell to about zero, the visual gain fell, the visual lead
rose, both crossover frequencies fell and the neuromuscular frequency and damping fell (Table
6.7). A fixed pilot model cannot show that. Here the pilot *chooses* its equalisation - visual
gain K_v, lead and lag t_lead, t_lag (Eq 6.5) and motion gain K_m (Eq 6.7) - and the tuning of
its neuromuscular system - omega_nm and zeta_nm (Eq 6.6), which a pilot sets by how stiffly
it holds the stick (in the optimal-control model the neuromuscular lag is itself an outcome of
the optimisation, through its control-rate weighting, Kleinman, Baron and Levison 1970; the
thesis found both changed with the filter, Table 6.7) - to minimise

    J = var(e) + r var(u)

for the motion system at hand, while its delays tau_v and tau_m stay its own (on request,
``adapted`` with ``"tau_v"``, the visual delay adapts too, traded against the visual remnant:
:func:`visual_noise_ratio`; tau_m does not: behind the filter K_m is zero and tau_m means
nothing, see the docs' Chapter 6 pages): the
optimal-control view of manual control (Kleinman, Baron and Levison 1970; McRuer's adjustment
rules, McRuer and Jex 1967, as the outcome), restricted to the structure of Eq 6.5-6.7 as in
Hess (1990) and Zaal et al. (2009). A stiffer, faster neuromuscular system passes more of the
remnant to the stick (var(u) rises), a slower one costs phase at crossover, so the optimum is
inside the physiological range: without the filter, where motion gives lead and the crossover
is high, the pilot tunes it faster than behind the filter, and its control activity is larger,
mainly through the remnant (as the thesis found, §6.4.1).

Everything is computed in the frequency domain, so one evaluation takes about a millisecond:

* the loop u = H_pe e^{-s T_d} e - H_ptheta (H_m theta + m) + n, theta = K H_theta,de (u + f_d),
  e = f_t - theta (Eq 6.3-6.7; H_m the motion system's pitch response, Eq 5.11 and its
  extensions; T_d the display's 25 ms);
* the forcing functions' lines (Table 6.2) give their parts of var(e) and var(u) exactly;
* the remnant is observation noise (Kleinman, Baron and Levison 1970): white noise on the
  displayed error and on the felt pitch rate, each with a density of ``noise_ratio`` times its
  signal's variance (on the felt rate times the pilot's ``motion_noise`` too: people perceive
  motion differently), so visual lead (which differentiates the visual noise) costs, and motion
  senses the rate directly; both variances depend on the noise they scale (a 2 x 2 linear
  system, required to be contracting);
* the motion noise m (Eq 5.10 heave at the pilot station, read as attitude -z / l, §6.3.5)
  where the configuration has it.

Stability is required (Nyquist's criterion on the disturbance open loop, :func:`stable`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy import optimize

from twin.chain.config import MotionSystem, resolve
from twin.chain.noise import HIGHPASS_ORDER, shaping_response
from twin.core.errors import SignalError
from twin.pilot.models.forcing import ForcingFunction, pitch_task
from twin.pilot.models.pitch import (
    PILOT_STATION_M,
    OpenLoops,
    PitchPilot,
    aircraft,
    motion_response,
    open_loops,
)

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: Equalisation the pilot adapts (Eq 6.5, 6.7).
EQUALISATION = ("k_v", "t_lead", "t_lag", "k_m")
#: Neuromuscular tuning the pilot adapts (Eq 6.6).
NEUROMUSCULAR = frozenset({"omega_nm", "zeta_nm"})
#: Parameters the pilot adapts: the equalisation and the neuromuscular tuning; the delays are
#: the pilot's own.
ADAPTED = (*EQUALISATION, "omega_nm", "zeta_nm")
#: Adaptable too, on request: the visual delay, traded against the visual remnant
#: (:func:`visual_noise_ratio`).
SPEED_ACCURACY = ("tau_v",)
#: Exponent k of the speed-accuracy trade-off: processing the visual error in tau_v instead of
#: the pilot's own tau_0 multiplies the visual observation noise by (tau_0 / tau_v)^k. An
#: assumption, chosen so that on the SRS baseline (condition 1, no filter) a pilot keeps about
#: its own delay (the default pilot: 0.310 s for its 0.300 s); with k = 2 every pilot would
#: process at about 0.21 s, with k = 8 above its own (the remnant is -20 dB: speed must cost
#: steeply to matter).
SPEED_ACCURACY_EXPONENT = 4.0
#: Range of the adapted visual delay, relative to the pilot's own.
TAU_V_RANGE = (0.5, 1.5)
#: Bounds of the adapted parameters (the neuromuscular ones a physiological range, about
#: twice either side of the 6-16 rad/s and 0.1-0.5 that pilot models identify).
BOUNDS = {"k_v": (0.05, 20.0), "t_lead": (0.0, 2.0), "t_lag": (0.02, 2.0), "k_m": (0.0, 3.0),
          "omega_nm": (3.0, 30.0), "zeta_nm": (0.05, 1.0)}  # fmt: skip
#: Weight r on var(u) in the cost (rad^2 / rad^2).
CONTROL_WEIGHT = 0.03
#: Observation-noise ratio of the remnant (-20 dB, Kleinman, Baron and Levison 1970).
NOISE_RATIO = 0.01
#: Starting equalisations (K_v, t_lead, t_lag, K_m) of the search, with and without motion
#: (the neuromuscular tuning starts from the pilot's given one).
STARTS = ((3.0, 0.2, 0.6, 0.5), (2.0, 0.3, 0.8, 0.0))
#: Cost given to unstable or remnant-dominated equalisations (relative to the start's).
UNSTABLE_COST = 1e6
#: Frequency grid of the Nyquist test [rad/s] (``|L| >> 1`` at its start, ``<< 1`` at its end).
STABILITY_GRID_RAD_S = np.geomspace(1e-2, 1e2, 3000)
#: Frequency grid of the remnant and noise integrals [rad/s].
GRID_RAD_S = np.geomspace(0.05, 200.0, 1500)


@dataclass(frozen=True)
class Task:
    """What the pilot adapts to: the forcing functions and the motion system.

    Attributes
    ----------
    config : MotionSystem
        The motion system.
    disturbance, target : ForcingFunction
        Table 6.2's forcing functions.

    """

    config: MotionSystem
    disturbance: ForcingFunction
    target: ForcingFunction
    _plant: dict = field(default_factory=dict, compare=False, repr=False)

    def plant(self, w: FloatArray) -> tuple[ComplexArray, ComplexArray]:
        """Aircraft K H and motion response H_m at ``w`` (cached per grid: they do not adapt)."""
        key = (w.size, float(w[0]), float(w[-1]))
        if key not in self._plant:
            self._plant[key] = (aircraft(w), motion_response(self.config, w))
        return self._plant[key]

    @classmethod
    def pitch(cls, config: MotionSystem | str) -> Task:
        """Return the Chapter 6 pitch task through ``config``."""
        cfg = resolve(config)
        fd, ft = pitch_task()
        return cls(cfg, fd, ft)


def _felt_noise_psd(config: MotionSystem, w: FloatArray) -> FloatArray:
    """One-sided PSD [rad^2 per rad/s] of the heave noise read as attitude at the pilot station."""
    block = config.noise_block()
    if block is None:
        return np.zeros_like(w)
    f = w / (2 * np.pi)
    s_acc = block.scale**2 * np.abs(shaping_response(f)) ** 2 * 2.0 / block.rate_hz  # per Hz
    if block.highpass_hz is not None:
        # |Butterworth high-pass|^2 of the generator's order (twin.chain.noise)
        s_acc = s_acc / (1 + (block.highpass_hz / np.maximum(f, 1e-9)) ** (2 * HIGHPASS_ORDER))
    s_z = s_acc / np.maximum(w, 1e-9) ** 4
    return s_z / PILOT_STATION_M**2 / (2 * np.pi)


@dataclass(frozen=True)
class Performance:
    """Predicted variances of a pilot's loop [rad^2] and its cost.

    Attributes
    ----------
    var_e, var_u : float
        Error and control variance (forcing functions, remnant and motion noise).
    var_rate : float
        Variance of the felt pitch rate [rad^2/s^2].
    cost : float
        var(e) + r var(u) (infinite when the remnant feeds itself: ``remnant_gain`` >= 1).
    remnant_gain : float
        Spectral radius of the remnant's feedback on the variances it scales with.

    """

    var_e: float
    var_u: float
    var_rate: float
    cost: float
    remnant_gain: float


def visual_noise_ratio(pilot: PitchPilot, own: PitchPilot, noise_ratio: float,
                       adapted: Sequence[str]) -> float | None:  # fmt: skip
    """Return the visual observation-noise ratio of ``pilot``, whose own delay is ``own``'s.

    Parameters
    ----------
    pilot : PitchPilot
        The pilot as it flies (its tau_v perhaps adapted).
    own : PitchPilot
        The pilot as it is: its tau_v is the one at which the visual noise is ``noise_ratio``.
    noise_ratio : float
        The pilot's observation-noise ratio at its own delays.
    adapted : sequence of str
        What the pilot adapts.

    Returns
    -------
    float or None
        None (the ratio is ``noise_ratio``) unless ``tau_v`` is
        ``adapted``; then ``noise_ratio (own.tau_v / pilot.tau_v)^k`` (k
        :data:`SPEED_ACCURACY_EXPONENT`).

    Notes
    -----
    A speed-accuracy trade-off (Wickelgren 1977): processing the error faster perceives it
    with more noise. The human's effective delay is not fixed: in the crossover model it
    falls as the forcing function's bandwidth rises (McRuer and Jex 1967), and the thesis read
    its lower tau_v behind the filter as faster visual processing where vision had to give
    the lead (§6.4.2.2).

    """
    if "tau_v" not in adapted:
        return None
    return noise_ratio * (own.tau_v / pilot.tau_v) ** SPEED_ACCURACY_EXPONENT


def performance(
    pilot: PitchPilot,
    task: Task,
    own: PitchPilot,
    weight: float,
    noise_ratio: float,
    adapted: Sequence[str],
    motion_noise: float = 1.0,
) -> Performance:
    """Predict how a subject flies ``task`` as ``pilot`` (:func:`predict`, its remnant its own).

    Parameters
    ----------
    pilot : PitchPilot
        The pilot as it flies.
    task : Task
        The task.
    own : PitchPilot
        The subject as it is (its own visual delay: :func:`visual_noise_ratio`).
    weight, noise_ratio : float
        The subject's r and observation-noise ratio at its own delays.
    adapted : sequence of str
        What the subject adapts.
    motion_noise : float
        Its felt rate's noise ratio relative to ``noise_ratio`` (:func:`adapt`).

    Returns
    -------
    Performance

    """
    visual = visual_noise_ratio(pilot, own, noise_ratio, adapted)
    return predict(pilot, task, weight, noise_ratio, visual, noise_ratio * motion_noise)


def predict(
    pilot: PitchPilot,
    task: Task,
    weight: float = CONTROL_WEIGHT,
    noise_ratio: float = NOISE_RATIO,
    visual_ratio: float | None = None,
    motion_ratio: float | None = None,
) -> Performance:
    """Predict var(e), var(u) and the cost of ``pilot`` flying ``task`` (frequency domain).

    The remnant is observation noise (Kleinman, Baron and Levison 1970): white, on the
    displayed error and on the felt pitch rate, each with a one-sided density of
    ``noise_ratio`` times its signal's variance per rad/s (the optimal-control model's
    V = pi rho E[y^2]); ``visual_ratio``, if given, replaces it on the displayed error
    (:func:`visual_noise_ratio`), ``motion_ratio`` on the felt rate (a subject who perceives
    motion less well than vision: :func:`adapt`'s ``motion_noise``). Visual lead
    differentiates the visual noise; the motion channel senses the rate directly. Both
    variances depend on the noise they scale: a 2 x 2 linear system.
    """
    cfg = task.config

    def responses(w: FloatArray) -> tuple[dict, dict, dict]:
        s = 1j * w
        hc, hm = task.plant(w)
        hpe = pilot.h_visual(w)
        hpm = pilot.h_ptheta(w)
        den = 1 + hc * (hpe + hpm * hm)
        # theta per input: target, disturbance, visual noise (on e), platform noise (attitude
        # at the station) and rate noise (on the felt rate)
        theta = {"t": hc * hpe / den, "d": hc / den, "v": hc * hpe / den, "m": -hc * hpm / den}
        theta["r"] = theta["m"] / s
        e = {k: (1.0 if k == "t" else 0.0) - v for k, v in theta.items()}
        u = {k: v / hc - (1.0 if k == "d" else 0.0) for k, v in theta.items()}
        rate = {k: s * (hm * v + (1.0 if k == "m" else 0.0)) for k, v in theta.items()}
        return e, u, rate

    forced = np.zeros(3)  # e, u, rate
    for key, ff in (("t", task.target), ("d", task.disturbance)):
        out = responses(ff.omega_rad_s)
        p = ff.amplitude**2 / 2
        forced += [float(np.sum(np.abs(x[key]) ** 2 * p)) for x in out]
    w = GRID_RAD_S
    out = responses(w)
    s_m = _felt_noise_psd(cfg, w)
    forced += [float(np.trapezoid(np.abs(x["m"]) ** 2 * s_m, w)) for x in out]
    # gains of the two observation noises (unit density) on e, u and rate
    gains = np.array([[float(np.trapezoid(np.abs(x[k]) ** 2, w)) for k in ("v", "r")]
                      for x in out])  # fmt: skip
    # [ve, vr] = forced[e, rate] + G diag(ratios) [ve, vr], G from the e and rate rows: each
    # noise's column scaled by its channel's ratio
    ratios = np.array([noise_ratio if visual_ratio is None else visual_ratio,
                       noise_ratio if motion_ratio is None else motion_ratio])  # fmt: skip
    g = gains[[0, 2]] * ratios
    radius = float(np.max(np.abs(np.linalg.eigvals(g))))
    if radius >= 1:
        return Performance(float("inf"), float("inf"), float("inf"), float("inf"), radius)
    ve, vr = np.linalg.solve(np.eye(2) - g, forced[[0, 2]])
    if ratios[0] == ratios[1]:  # one ratio for both channels: summed as it always was
        vu = forced[1] + ratios[0] * (gains[1, 0] * ve + gains[1, 1] * vr)
    else:
        vu = forced[1] + ratios[0] * gains[1, 0] * ve + ratios[1] * gains[1, 1] * vr
    return Performance(float(ve), float(vu), float(vr), float(ve + weight * vu), radius)


def stable(pilot: PitchPilot, task: Task) -> bool:
    """Whether the closed loop is stable (Nyquist's criterion on 1 + L, L the disturbance loop).

    L = K H (H_pe e^{-s T_d} + H_ptheta H_m) has one pole at the origin (the aircraft's
    integrator, K0 / s with K0 > 0) and none in the right half-plane, so the loop is stable
    when the phase of 1 + L, unwrapped from -90 deg just above 0 rad/s, ends at 0 (not at a
    multiple of -360 deg) where L has died out.
    """
    w = STABILITY_GRID_RAD_S
    hc, hm = task.plant(w)
    hpe = pilot.h_visual(w)
    loop = hc * (hpe + pilot.h_ptheta(w) * hm)
    phase = np.unwrap(np.angle(1 + loop))
    return bool(abs(phase[-1] - phase[0] - np.pi / 2) < np.pi / 2)


@dataclass(frozen=True)
class Adapted:
    """A pilot adapted to a task.

    Attributes
    ----------
    pilot : PitchPilot
        The adapted pilot (delays as given; equalisation and neuromuscular tuning optimal).
    performance : Performance
        Its predicted variances and cost.
    loops : OpenLoops
        Crossover frequencies and phase margins.
    config : str
        The motion configuration's name.
    adapted : tuple of str
        The parameters that were adapted (the others are the pilot's own).

    """

    pilot: PitchPilot
    performance: Performance
    loops: OpenLoops
    config: str
    adapted: tuple[str, ...] = ADAPTED

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: parameters, predicted variances [deg^2], crossovers and margins."""
        deg2 = (180 / np.pi) ** 2
        return {
            "config": self.config,
            "pilot": dataclasses.asdict(self.pilot),
            "adapted": list(self.adapted),
            "var_e_deg2": self.performance.var_e * deg2,
            "var_u_deg2": self.performance.var_u * deg2,
            "cost": self.performance.cost,
            "crossover_disturbance_rad_s": self.loops.crossover_d,
            "phase_margin_disturbance_deg": self.loops.phase_margin_d,
            "crossover_target_rad_s": self.loops.crossover_t,
            "phase_margin_target_deg": self.loops.phase_margin_t,
        }

    def format(self) -> str:
        """Plain-text summary."""
        p = self.pilot
        d = self.to_dict()
        return "\n".join([
            f"pilot adapted to {self.config} (minimises var(e) + r var(u))",
            f"  K_v {p.k_v:.3f}  t_lead {p.t_lead:.3f} s  t_lag {p.t_lag:.3f} s  "
            f"K_m {p.k_m:.3f} s",
            f"  neuromuscular ({'adapted' if NEUROMUSCULAR & set(self.adapted) else 'its own'}): "
            f"omega_nm {p.omega_nm:.2f} rad/s  zeta_nm {p.zeta_nm:.2f}",
            (f"  visual delay (adapted: speed against visual remnant): tau_v {p.tau_v:.3f} s  "
             f"motion delay (its own): tau_m {p.tau_m:.3f} s" if "tau_v" in self.adapted else
             f"  delays (its own): tau_v {p.tau_v:.3f} s  tau_m {p.tau_m:.3f} s"),
            f"  var(e) {d['var_e_deg2']:.3f} deg^2  var(u) {d['var_u_deg2']:.3f} deg^2",
            f"  disturbance loop: crossover {self.loops.crossover_d:.2f} rad/s, "
            f"phase margin {self.loops.phase_margin_d:.1f} deg",
            f"  target loop: crossover {self.loops.crossover_t:.2f} rad/s, "
            f"phase margin {self.loops.phase_margin_t:.1f} deg",
        ])  # fmt: skip


def adapted_names(adapted: Sequence[str]) -> tuple[str, ...]:
    """Check a choice of adapted parameters and return it in :data:`ADAPTED` order.

    Raises
    ------
    SignalError
        None given, a bare string, or a name not among :data:`ADAPTED` and
        :data:`SPEED_ACCURACY`.

    """
    if isinstance(adapted, str):
        raise SignalError(f"adapted parameters must be a sequence of names; got the string "
                          f"{adapted!r}")  # fmt: skip
    allowed = (*ADAPTED, *SPEED_ACCURACY)
    unknown = sorted(set(adapted) - set(allowed))
    if unknown or not adapted:
        raise SignalError(f"adapted parameters must be among {', '.join(allowed)}; got "
                          f"{', '.join(map(str, unknown)) or 'none'}")  # fmt: skip
    return tuple(k for k in allowed if k in adapted)


def adapt(
    task: Task | MotionSystem | str,
    limitations: PitchPilot | None = None,
    weight: float = CONTROL_WEIGHT,
    noise_ratio: float = NOISE_RATIO,
    starts: Sequence[PitchPilot] | None = None,
    adapted: Sequence[str] = ADAPTED,
    motion_noise: float = 1.0,
) -> Adapted:
    """Choose the parameters ``adapted`` (:data:`ADAPTED`) that minimise the cost on ``task``.

    Parameters
    ----------
    task : Task, MotionSystem or str
        The pitch task through a motion configuration (a configuration name or object is the
        Chapter 6 pitch task through it).
    limitations : PitchPilot, optional
        The pilot whose delays (and every parameter not in ``adapted``) are kept, and whose
        neuromuscular tuning starts the search (Eq 6.5-6.7 defaults). Where ``tau_v`` is
        adapted, its tau_v is the pilot's own, against which faster processing costs visual
        remnant (:func:`visual_noise_ratio`; searched over :data:`TAU_V_RANGE` times it).
    weight : float
        r in J = var(e) + r var(u) (> 0).
    noise_ratio : float
        Observation-noise ratio of the remnant (> 0; :func:`predict`).
    starts : sequence of PitchPilot, optional
        Starting points (:data:`STARTS` on the ``limitations`` pilot by default).
    adapted : sequence of str
        The parameters the pilot adapts, among :data:`ADAPTED` and :data:`SPEED_ACCURACY`
        (``EQUALISATION`` keeps the neuromuscular system fixed, as a pilot model with fixed
        limitations; ``(*ADAPTED, "tau_v")`` adapts the visual delay too).
    motion_noise : float
        The felt rate's observation-noise ratio relative to ``noise_ratio`` (> 0; 1: the
        pilot perceives both alike; above 1 it perceives motion less well, and uses it less).

    Raises
    ------
    SignalError
        A weight or ratio out of range, an unknown adapted parameter, a visual delay to adapt
        that is not positive, or no stable equalisation found.

    """
    if not np.isfinite(weight) or weight <= 0:
        raise SignalError(f"control weight r must be > 0; got {weight}")
    if not np.isfinite(noise_ratio) or noise_ratio <= 0:
        raise SignalError(f"observation-noise ratio must be > 0; got {noise_ratio}")
    if not (np.isfinite(motion_noise) and motion_noise > 0
            and np.isfinite(noise_ratio * motion_noise)):  # fmt: skip
        raise SignalError(f"the motion channel's noise relative to the visual must be a finite "
                          f"number > 0; got {motion_noise}")  # fmt: skip
    names = adapted_names(adapted)
    t = task if isinstance(task, Task) else Task.pitch(task)
    base = limitations or PitchPilot()
    if "tau_v" in names and not base.tau_v > 0:
        raise SignalError(f"a visual delay to adapt must be > 0 s (the pilot's own, which "
                          f"faster processing is measured against); got {base.tau_v}")  # fmt: skip
    bounds = {**BOUNDS, "tau_v": tuple(base.tau_v * f for f in TAU_V_RANGE)}
    lo = np.array([bounds[k][0] for k in names])
    hi = np.array([bounds[k][1] for k in names])

    def pilot_of(x: FloatArray) -> PitchPilot:
        return dataclasses.replace(base, **dict(zip(names, np.clip(x, lo, hi), strict=True)))

    def performance_of(p: PitchPilot) -> Performance:
        return performance(p, t, base, weight, noise_ratio, names, motion_noise)

    def cost(x: FloatArray) -> float:
        p = pilot_of(x)
        perf = performance_of(p)
        if not np.isfinite(perf.cost) or perf.remnant_gain >= 0.95 or not stable(p, t):
            return UNSTABLE_COST
        return perf.cost / scale

    scale = predict(base, t, weight, noise_ratio, motion_ratio=noise_ratio * motion_noise).cost
    scale = scale if np.isfinite(scale) and scale > 0 else 1.0
    firsts = list(starts) if starts else [
        dataclasses.replace(base, **dict(zip(EQUALISATION, x, strict=True))) for x in STARTS
    ]  # fmt: skip
    best = None
    for s in firsts:
        x0 = np.clip([getattr(s, k) for k in names], lo, hi)
        if cost(x0) >= UNSTABLE_COST:
            continue
        options = {"xatol": 1e-3, "fatol": 1e-6, "maxiter": 300 * len(names)}
        r = optimize.minimize(cost, x0, method="Nelder-Mead", options=options)
        if r.fun < UNSTABLE_COST and (best is None or r.fun < best.fun):
            best = r
    if best is None:
        raise SignalError(f"no stable equalisation found for {t.config.name}")
    p = pilot_of(best.x)
    perf = performance_of(p)
    return Adapted(p, perf, open_loops(p, t.config), t.config.name, names)
