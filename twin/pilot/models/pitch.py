"""Chapter 6's pitch tracking task flown through a motion configuration of the twin.

The task (§6.3.1, Fig 6.3): the Cessna Citation pitch dynamics of Eq 6.3 behind the stick gain
K = -0.2865, the disturbance f_d acting on the control signal and the target f_t of Table 6.2,
the compensatory display 25 ms late. The pilot (Eq 6.5-6.7) sees the error and feels the motion
the motion system actually produces: the configuration's whole chain (every block and
extension of :meth:`~twin.chain.config.MotionSystem.blocks`, the actuator limits, the heave
noise; :class:`twin.chain.stream.ChainStream`, the same stream as open-loop runs) stepped one
loop sample at a time, on the reduced (Eq 5.11) or the full MuJoCo platform,
plus the heave noise of Eq 5.10 at the pilot station, 3.2 m ahead of the c.g., where a heave
offset z reads as a pitch attitude -z / l (the model's single motion response combines pitch
and pitch-heave, §6.3.5):

    u = H_pe e_display - H_ptheta theta_felt + n,   theta = K H_theta,de (u + f_d)

Runs are simulated at 100 Hz, vectorised over runs and in blocks of the pilot's shorter delay
(:mod:`twin.pilot.models.pitch_loop`, as :mod:`twin.pilot.models.loop`). Crossover
frequencies and phase margins of the disturbance and target open loops come from
python-control's ``stability_margins`` on the analytic open loops (Eq 5.11 motion).

What it leaves out: the c.g. heave (negligible, §6.3.1) and any adaptation of the pilot: the
pilot model is fixed across conditions, so the effects are those of the motion alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal

from twin.chain.config import MotionSystem, resolve
from twin.chain.physics import FullPlatform
from twin.chain.reduced import ReducedPlatform
from twin.chain.response import PlatformResponse
from twin.chain.stepping import Platform
from twin.chain.stream import ChainStream
from twin.core.errors import SignalError
from twin.core.progress import ProgressFn
from twin.pilot.models.forcing import MEASUREMENT_S, RATE_HZ, RUN_IN_S, ForcingFunction, pitch_task
from twin.pilot.models.loop import Remnant, _bilinear, _Filter
from twin.pilot.models.model import neuromuscular
from twin.pilot.models.pitch_loop import HEAVE, PITCH, PitchLoop, WithPassive, fly

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: Eq 6.3: pitch attitude per elevator deflection (numerator, denominator in s).
AIRCRAFT = (-10.6189 * np.array([1.0, 0.9906]), np.array([1.0, 2.756, 7.612, 0.0]))
#: Stick gain K_de,u (§6.3.1), pilot station ahead of the c.g. [m], display latency [s].
STICK_GAIN, PILOT_STATION_M, DISPLAY_DELAY_S = -0.2865, 3.2, 0.025
#: Frequency points (0.1-50 rad/s, log-spaced) of the open loops whose margins are computed.
MARGIN_POINTS = 500
#: Most runs one call flies (about 0.3 MB and 0.02 s a run on the reduced platform).
MAX_RUNS = 1000
#: Gravity [m/s^2] (the tilt a passive path feels, :class:`Feedthrough`).
G = 9.81


@dataclass(frozen=True)
class PitchPilot:
    """The multi-modal pilot of Eq 6.5-6.7.

    The thesis gives its estimates only as figures (Fig 6.8, 6.9); these defaults are
    illustrative values for this task (on the SRS baseline: disturbance crossover 3.3 rad/s with
    53 deg of phase margin, target crossover 0.6 rad/s), not the thesis' numbers.

    Attributes
    ----------
    k_v, t_lead, t_lag, tau_v : float
        Visual gain [-], lead and lag time constants [s], visual delay [s] (Eq 6.5).
    k_m, tau_m : float
        Motion gain [s] and motion delay [s] (Eq 6.7).
    omega_nm, zeta_nm : float
        Neuromuscular frequency [rad/s] and damping [-] (Eq 6.6).

    """

    k_v: float = 1.5
    t_lead: float = 0.2
    t_lag: float = 0.1
    tau_v: float = 0.30
    k_m: float = 0.35
    tau_m: float = 0.20
    omega_nm: float = 11.0
    zeta_nm: float = 0.25

    def nm(self, w: ArrayLike) -> ComplexArray:
        """H_nm of Eq 6.6."""
        return neuromuscular(w, self.omega_nm, self.zeta_nm)

    def h_pe(self, w: ArrayLike) -> ComplexArray:
        """Eq 6.5 (without the display latency)."""
        s = 1j * np.asarray(w, dtype=float)
        lead = (1 + self.t_lead * s) ** 2 / (1 + self.t_lag * s)
        return self.k_v * lead * np.exp(-s * self.tau_v) * self.nm(w)

    def h_visual(self, w: ArrayLike) -> ComplexArray:
        """Eq 6.5 on the error as displayed: H_pe e^{-s T_d} (the display's 25 ms included)."""
        return self.h_pe(w) * np.exp(-1j * np.asarray(w, dtype=float) * DISPLAY_DELAY_S)

    def h_ptheta(self, w: ArrayLike) -> ComplexArray:
        """Eq 6.7: response to the felt pitch attitude."""
        s = 1j * np.asarray(w, dtype=float)
        return self.k_m * s * np.exp(-s * self.tau_m) * self.nm(w)


@dataclass(frozen=True)
class Feedthrough:
    """A passive path from the felt pitch motion to the stick, not in Eq 6.5-6.7.

    Biodynamic feedthrough: the specific force along the stick at the hand moves the arm,
    whose admittance is taken as the pilot's neuromuscular system (Eq 6.6), with no neural
    delay (one loop sample, the loop's step). For a hand ``height_m`` above the pitch axis
    the force per felt attitude is h s^2 - g (the tangential acceleration of the hand, less
    the tilt of gravity), so the stick moves by

        u_b = -gain (h s^2 - g) H_nm(s) theta_felt,

    whose force is in phase with the attitude at every frequency (h s^2 - g is -(h w^2 + g)
    at s = jw), while Eq 6.7's -K_m s e^{-s tau_m} (its sign in u) is 90 deg from it less the
    delay's lag, for any K_m >= 0 and tau_m >= 0: both share H_nm, and the MLE of Eq 6.5-6.7
    can only absorb the path in biased parameters (``evidence["fit"]`` of
    :func:`twin.pilot.identification.mle.fit_pitch_pilot` shows the misfit). The path is positive
    feedback (the hand pushed aft as the nose rises); a large one destabilises the loop. An
    assumption for exploring what the thesis' estimates may hold
    (Venrooij et al. measured such paths; no value for the SRS side-stick is given), not a
    measured property of the SRS.

    Attributes
    ----------
    gain : float
        Stick per specific force [u per m/s^2], >= 0.
    height_m : float
        Height of the hand above the pitch axis [m], >= 0.

    """

    gain: float
    height_m: float = 1.0

    def __post_init__(self) -> None:
        """Check the gain and height."""
        for name in ("gain", "height_m"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise SignalError(f"feedthrough {name} must be a finite number >= 0; got {v}")

    @classmethod
    def relative(cls, ratio: float, pilot: PitchPilot, w: float = 3.0, height_m: float = 1.0
                 ) -> Feedthrough:  # fmt: skip
        """Return the path whose magnitude at ``w`` [rad/s] is ``ratio`` of ``pilot``'s Eq 6.7."""
        return cls(ratio * pilot.k_m * w / (height_m * w**2 + G), height_m)

    def numerator(self, w2: float) -> FloatArray:
        """Return -u_b / theta_felt's numerator over H_nm's denominator (``w2``: omega_nm^2)."""
        return self.gain * w2 * np.array([self.height_m, 0.0, -G])


def aircraft(w: ArrayLike) -> ComplexArray:
    """K H_theta,de at ``w`` [rad/s]: pitch attitude per control signal (Eq 6.3 with K)."""
    s = 1j * np.asarray(w, dtype=float)
    return STICK_GAIN * np.polyval(AIRCRAFT[0], s) / np.polyval(AIRCRAFT[1], s)


def motion_response(config: MotionSystem, w: ArrayLike) -> ComplexArray:
    """Felt over simulated pitch attitude: the configuration's filter and delay (Eq 5.11)."""
    return config.response_at_hz(np.asarray(w, dtype=float) / (2 * np.pi))[:, PITCH]


@dataclass(frozen=True)
class OpenLoops:
    """Crossover frequencies [rad/s] and phase margins [deg] of the two open loops (§6.4.2.1).

    The crossover is the 0 dB crossing with the smallest phase margin (python-control's
    ``stability_margins``).

    Attributes
    ----------
    crossover_d, phase_margin_d : float
        Disturbance open loop, K H (H_pe e^{-s T_d} + H_ptheta H_m).
    crossover_t, phase_margin_t : float
        Target open loop, H_pe e^{-s T_d} K H / (1 + H_ptheta H_m K H).
    motion_lead_phase_deg : float
        Phase of the felt motion cue relative to the true attitude at the disturbance crossover
        (the lead the motion channel can provide is lost by this much).

    """

    crossover_d: float
    phase_margin_d: float
    crossover_t: float
    phase_margin_t: float
    motion_lead_phase_deg: float


def open_loop_responses(
    pilot: PitchPilot, config: MotionSystem, w: ArrayLike
) -> dict[str, ComplexArray]:
    """Return the disturbance (``d``) and target (``t``) open loops at ``w`` [rad/s]."""
    hc = aircraft(w)
    hpe = pilot.h_visual(w)
    hm = pilot.h_ptheta(w) * motion_response(config, w)
    return {"d": hc * (hpe + hm), "t": hpe * hc / (1 + hm * hc)}


def open_loops(pilot: PitchPilot, config: MotionSystem) -> OpenLoops:
    """Crossovers and phase margins of the disturbance and target open loops."""
    import control  # here, not at the top: it imports matplotlib.pyplot (0.4 s per process)

    # python-control interpolates the response between the points for its crossings: 500 give
    # the margins of 4000 to 1e-7 in an eighth of the time
    w = np.geomspace(0.1, 50.0, MARGIN_POINTS)
    loops = open_loop_responses(pilot, config, w)
    out = {}
    for name, h in loops.items():
        # the gain crossing with the smallest phase margin (python-control's choice): with
        # motion lead the disturbance loop can cross 0 dB more than once
        _, pm, _, _, wgc, _ = control.stability_margins(control.frd(h, w))
        if not np.isfinite(wgc):
            raise SignalError(f"the {name} open loop never crosses 0 dB between 0.1 and 50 rad/s")
        out[name] = (float(wgc), float(pm))
    lead = float(np.degrees(np.angle(motion_response(config, [out["d"][0]])[0])))
    return OpenLoops(out["d"][0], out["d"][1], out["t"][0], out["t"][1], lead)


@dataclass(frozen=True, eq=False)
class PitchRuns:
    """Signals of the measurement windows of several runs, shape (runs, samples).

    Attributes
    ----------
    t : ndarray
        Time [s] from the window's start.
    e, u, theta, theta_felt, n : ndarray
        Error, control, pitch attitude, felt pitch attitude and remnant [rad].
    ft, fd : ndarray, shape (samples,)
        Forcing functions over the window.
    config : MotionSystem
        The motion configuration.

    """

    t: FloatArray
    e: FloatArray
    u: FloatArray
    theta: FloatArray
    theta_felt: FloatArray
    n: FloatArray
    ft: FloatArray
    fd: FloatArray
    config: MotionSystem


def simulate_pitch(
    pilot: PitchPilot,
    config: MotionSystem | str,
    runs: int = 1,
    seed: int = 0,
    remnant_scale: float = 0.0,
    rate_hz: float = RATE_HZ,
    model: str = "reduced",
    progress: ProgressFn | None = None,
    feedthrough: Feedthrough | None = None,
) -> PitchRuns:
    """Fly the pitch task through a motion configuration (run-in 8.08 s, window 81.92 s).

    Parameters
    ----------
    pilot : PitchPilot
        The pilot.
    config : MotionSystem or str
        Motion configuration (``srs``, ``condition-1`` ... ``condition-8``, ...).
    runs : int
        Runs with fresh remnant and noise.
    seed : int
        Seed of remnant and motion noise.
    remnant_scale : float
        Gain on the Eq 2.21-shaped unit remnant (0: none).
    rate_hz : float
        Simulation rate [Hz].
    model : str
        ``"reduced"`` (Eq 5.11) or ``"full"`` (the MuJoCo platform in the loop), behind the
        configuration's whole chain (:class:`twin.chain.stream.ChainStream`, as open loop).
    progress : callable, optional
        Called with the flown time about every 2 % of the run (:mod:`twin.core.progress`).
    feedthrough : Feedthrough, optional
        A passive path from the felt motion to the stick beside the pilot's (none by
        default; with one the loop and its motion chain are stepped one sample at a time:
        about 3x slower on the reduced platform, far slower on the full one; a motion
        delay below half a sample then acts one sample late).

    """
    cfg = resolve(config)
    loop = pitch_loop(pilot, cfg, runs, seed, remnant_scale, rate_hz, model, progress,
                      feedthrough)  # fmt: skip
    out, start, t = fly(loop), loop.start, loop.t
    window = slice(start, t.size)
    return PitchRuns(t[window] - t[start], out["e"], out["u"], out["theta"], out["theta_felt"],
                     out["n"], loop.f_t[window], loop.f_d[window], cfg)  # fmt: skip


def pitch_loop(
    pilot: PitchPilot,
    cfg: MotionSystem,
    runs: int,
    seed: int,
    remnant_scale: float,
    rate_hz: float,
    model: str,
    progress: ProgressFn | None = None,
    feedthrough: Feedthrough | None = None,
) -> PitchLoop:
    """Return what :func:`simulate_pitch` flies (the arguments are its own), ready to fly."""
    if model not in ("reduced", "full"):
        raise SignalError(f"model must be 'reduced' or 'full'; got {model!r}")
    if not 1 <= runs <= MAX_RUNS:
        raise SignalError(f"runs must be in [1, {MAX_RUNS}]; got {runs}")
    fd, ft = pitch_task()
    dt = 1.0 / rate_hz
    start = round(RUN_IN_S * rate_hz)
    n_keep = round(MEASUREMENT_S * rate_hz)
    t = np.arange(start + n_keep) / rate_hz
    f_t, f_d = ft(t), fd(t)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 2]))
    # aircraft (Eq 6.3 with K) by zero-order hold, pilot channels by the bilinear transform
    ad, bd, _, _, _ = signal.cont2discrete(
        signal.tf2ss(STICK_GAIN * AIRCRAFT[0], AIRCRAFT[1]), dt, method="zoh"
    )
    w2 = pilot.omega_nm**2
    nm_den = [1.0, 2 * pilot.zeta_nm * pilot.omega_nm, w2]
    pe_num = pilot.k_v * w2 * np.polymul([pilot.t_lead, 1.0], [pilot.t_lead, 1.0])
    pe = _Filter(*signal.bilinear(pe_num, np.polymul(nm_den, [pilot.t_lag, 1.0]), fs=rate_hz),
                 runs)  # fmt: skip
    # a pilot who does not use the motion (K_m = 0, as behind the 1 Hz filter) has no channel
    pm = _Filter(*signal.bilinear(pilot.k_m * w2 * np.array([1.0, 0.0]), nm_den, fs=rate_hz),
                 runs) if pilot.k_m else None  # fmt: skip
    remnant = Remnant(rng, remnant_scale, runs, rate_hz) if remnant_scale else None
    chain = pitch_chain(cfg, model, rate_hz, runs, seed)
    a_c, b_c, c_c, _ = signal.tf2ss(STICK_GAIN * AIRCRAFT[0], AIRCRAFT[1])
    # attitude jets from the aircraft state; the input held over the last interval (ZOH)
    jet_x = np.stack([c_c[0], c_c[0] @ a_c, c_c[0] @ a_c @ a_c])  # (3, nx)
    jet_u = np.array([0.0, float(c_c[0] @ b_c[:, 0]), float(c_c[0] @ a_c @ b_c[:, 0])])
    d_v, d_m = round((pilot.tau_v + DISPLAY_DELAY_S) * rate_hz), round(pilot.tau_m * rate_hz)
    if feedthrough is not None:
        # the passive path acts one sample late, the pilot's motion channel d_m late
        passive = _Filter(*_bilinear(feedthrough.numerator(w2), nm_den, rate_hz), runs)
        pm, d_m = WithPassive(pm, d_m, passive, runs), 1
    return PitchLoop(pe, pm, d_v, d_m, remnant, chain, felt_attitude, ad, bd, jet_x, jet_u,
                     PILOT_STATION_M, t, f_t, f_d, dt, start, progress)  # fmt: skip


def pitch_chain(
    config: MotionSystem, model: str, rate_hz: float, runs: int, seed: int
) -> ChainStream:
    """Return the configuration's chain with the reduced or the full platform, for ``runs`` runs.

    The reduced platform is sampled at the loop rate; the full one steps its physics through
    each loop interval. Run ``i``'s heave noise draws from ``SeedSequence([seed, 3, i])``.
    """
    if model == "full":
        platform: Platform = FullPlatform(config.platform)
    else:
        platform = ReducedPlatform(config.platform, rate_hz=rate_hz)
    seeds = [int(np.random.SeedSequence([seed, 3, i]).generate_state(1)[0]) for i in range(runs)]
    return ChainStream(config, platform, rate_hz, seed=seeds)


def felt_attitude(response: PlatformResponse, station_m: float, times: FloatArray) -> FloatArray:
    """Return the pitch attitude felt at the loop's sample ``times``, shape (runs, len(times)).

    The cabin's pitch, plus the heave at the pilot station that is not the commanded
    pitch-heave read as attitude, -(z - z_cmd) / l (the heave noise of Eq 5.10, and on the
    full platform its own heave error): the model's single motion channel combines pitch and
    pitch-heave (§6.3.5).
    """
    rows = np.clip(np.searchsorted(response.t, times - 1e-9), 0, response.t.size - 1)
    pose, command = response.pose[:, rows], response.command[:, rows]
    return pose[..., PITCH] - (pose[..., HEAVE] - command[..., HEAVE]) / station_m


def variance_decomposition(
    x: FloatArray, fd: ForcingFunction, ft: ForcingFunction
) -> dict[str, float]:
    """Variance of ``x`` (runs, samples) split into target, disturbance and remnant (§6.4.1).

    The power at the target lines, at the disturbance lines, and everything else (averaged
    over runs), as Jex and Magdaleno (1978) split it.
    """
    n = x.shape[-1]
    p = 2 * np.abs(np.fft.rfft(x - x.mean(axis=-1, keepdims=True), axis=-1)) ** 2 / n**2
    p = p.mean(axis=0)
    target, dist = p[ft.bins()].sum(), p[fd.bins()].sum()
    return {"target": float(target), "disturbance": float(dist),
            "remnant": float(p.sum() - target - dist)}  # fmt: skip
