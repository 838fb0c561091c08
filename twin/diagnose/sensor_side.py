"""Sensor or platform: a sensor filter's lines are a platform lag's; the noise tells them apart.

A first-order low-pass at f_c inside the IMU, on the DOF's own channel (``sensor_filter``),
and a first-order lag t_m = 1 / (2 pi f_c) of the platform in that DOF (``platform_lag``,
Eq 5.11's t_m: a heavier cabin behind the same PD) multiply every excited line by the same
factor: the lines cannot tell them apart. The noise can. A filter inside the sensor filters
the sensor's own noise too (its spectrum falls above f_c); a platform lag leaves the sensor's
noise as it is. So after the lines have named a ``sensor_filter``, both readings are scored
on the measurement's noise up to :data:`SIDE_BAND_HZ` (above the lines' default band of
15 Hz, ``--max-hz``), where a filter shows most (the off-line bins of
:mod:`twin.diagnose.nuisance`, the IMU's noise level fitted as a nuisance for each, or held at
``--imu-noise``)::

    evidence = 2 (log L_platform - log L_sensor)

- above ``BIC_MARGIN``: the platform lag is named instead (the same line response, so the
  same held-out gains; the sensor's noise above f_c is unfiltered);
- below ``-BIC_MARGIN``: the sensor filter stays (the noise is filtered as it is);
- in between, or where the band reaches less than an octave above f_c (too little of the
  noise is filtered to tell: a 20 Hz cutoff below the 30 Hz top), the noise cannot tell: the
  sensor filter stays named, and the judgement says that the platform lag explains the lines
  as well, with the evidence;
- where the runs disagree (one beyond the margin each way), the side is undecided too: a
  run's off-line power is then not the IMU's noise alone (a designed run with lines at the
  platform's limits puts power between its lines: Table 5.2's two runs read -750 and -460, a
  sensor filter, and a designed run at 10-15 Hz of the same truth +3600).

The same noise weighs the named set's alternatives (:func:`rule_out_by_noise`): where it
shows the sensor filter the lines named (verdict ``sensor``), an alternative without a sensor
filter (a delay with a resonance, say, which can match the lines as well) leaves the filtered
noise unexplained: the noise's evidence against it is beyond the margin on top of whatever the
lines hold against it. It is listed as ruled out by the noise, not as an alternative.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from twin.chain.extensions import Extension
from twin.diagnose.candidates import Model, make_extension
from twin.diagnose.nuisance import fit_noise
from twin.diagnose.residuals import Segment, segment
from twin.diagnose.select import BIC_MARGIN, MAX_ALTERNATIVES, Finding, describe_alternative

#: Top of the band the two readings' noise is scored on [Hz]. The nominal noise model follows
#: the measured noise up to about 30 Hz of the 100 Hz analysis grid; above it the IMU
#: processing's roll-off (App. C.2.3) is not matched: on SRS pitch and roll runs with either
#: truth, the right reading's IMU-noise factor rises from about 0.8 at 30 Hz to 7-16 at 50 Hz
#: and the evidence turns to the platform for a true sensor filter. Up to 30 Hz the evidence
#: was -480 to -960 for sensor filters at 3 and 8 Hz, +34 to +415 for platform lags.
SIDE_BAND_HZ = 30.0


def platform_reading(sensor: Extension, dof: str) -> Extension:
    """Return the ``platform_lag`` of ``dof`` with a ``sensor_filter``'s line response."""
    return Extension("platform_lag", {"lag_s": 1.0 / (2 * np.pi * sensor.value("cutoff_hz"))},
                     (dof,))  # fmt: skip


#: Named effects that put power off the lines themselves (a backlash's harmonics): beside
#: them the off-line noise cannot say whether the sensor filters it, so the side is left
#: undecided (a run at rest, noise alone, decides).
OFF_LINE_EFFECTS = ("backlash",)


@dataclass(frozen=True)
class SideJudgement:
    """Whether a ``sensor_filter`` the lines named is in the sensor or the platform.

    Attributes
    ----------
    sensor, platform : Extension
        The two readings (the same line response).
    evidence : float
        2 (log L_platform - log L_sensor) of the measurement's noise.
    verdict : str
        ``"platform"``, ``"sensor"`` or ``"undecided"`` (see the module docstring).
    per_run : tuple of float
        The evidence of each run alone.

    """

    sensor: Extension
    platform: Extension
    evidence: float
    verdict: str
    per_run: tuple[float, ...] = ()

    def to_json(self) -> dict[str, object]:
        """JSON-ready, with what it means."""
        meaning = {
            "platform": "the sensor's noise above the cutoff is not filtered: the lag is the "
            "platform's",
            "sensor": "the sensor's noise is filtered as the lines' cutoff says: the filter "
            "is in the sensor",
            "undecided": "the noise cannot tell a filter in the sensor from a lag of the "
            "platform: both explain the lines; a run whose noise is measured up to at "
            "least twice the cutoff (a rest run at the IMU's full rate) decides",
        }[self.verdict]
        if (
            self.verdict == "undecided"
            and self.per_run
            and (max(self.per_run) > BIC_MARGIN and min(self.per_run) < -BIC_MARGIN)
        ):
            meaning = (
                "the runs disagree (noise evidence for the platform per run: "
                + ", ".join(f"{e:+.0f}" for e in self.per_run)
                + "): the off-line power of some is not the IMU's noise alone; "
                + meaning.split(": ", 1)[1]
            )
        return {"sensor": self.sensor.to_json(), "platform": self.platform.to_json(),
                "noise_evidence_platform_over_sensor": self.evidence,
                "noise_evidence_per_run": list(self.per_run),
                "verdict": self.verdict, "meaning": meaning}  # fmt: skip


def side_text(side: dict) -> str:
    """One line for a report or a terminal: the judgement of a finding's ``evidence["side"]``."""
    other = side["platform"] if side["verdict"] != "platform" else side["sensor"]
    reading = Extension.from_json(other).describe()
    evidence = side["noise_evidence_platform_over_sensor"]
    return (f"sensor or platform: {side['meaning']} (noise evidence for the platform "
            f"{evidence:+.0f}; the other reading: {reading})")  # fmt: skip


def judge_side(model: Model, imu_noise: float | None = None) -> SideJudgement | None:
    """Weigh the ``sensor_filter`` of a fitted model against its platform lag, on the noise.

    Parameters
    ----------
    model : Model
        The DOF's fitted model (the named extensions).
    imu_noise : float, optional
        The IMU's noise over its data sheet's (amplitude) when known; otherwise fitted for each
        reading as a nuisance.

    Returns
    -------
    SideJudgement or None
        None where the model has no ``sensor_filter``.

    """
    sensor = next((e for e in model.extensions if e.effect == "sensor_filter"), None)
    if sensor is None:
        return None
    platform = platform_reading(sensor, model.dof)
    others = [e for e in model.extensions if e is not sensor]
    alternative = Model(model.case, model.dof, [*others, platform], model.anchor, model._cache)
    segments = [segment(c, max_hz=SIDE_BAND_HZ) for c in model.case.of(model.dof)]
    known = None if imu_noise is None else float(imu_noise) ** 2
    evidence, per_run = noise_evidence(alternative, model, segments, known)
    beside = any(e.effect in OFF_LINE_EFFECTS for e in others)
    verdict = side_verdict(evidence, per_run, sensor.value("cutoff_hz"), beside)
    return SideJudgement(sensor, platform, float(evidence), verdict, tuple(per_run))


def noise_evidence(
    a: Model, b: Model, segments: Sequence[Segment], imu_fixed: float | None
) -> tuple[float, list[float]]:
    """Return ``2 (log L_a - log L_b)`` of the noise over every run, and of each run alone.

    Each model's noise power factors are fitted (the IMU's held at ``imu_fixed`` when known).
    With one run, its own evidence is the total.
    """

    def loglik(m: Model, segs: Sequence[Segment]) -> float:
        return fit_noise(m, segs, imu_fixed=imu_fixed).loglik

    total = 2.0 * (loglik(a, segments) - loglik(b, segments))
    if len(segments) < 2:
        return total, [total]
    return total, [2.0 * (loglik(a, [g]) - loglik(b, [g])) for g in segments]


def side_verdict(
    evidence: float, per_run: Sequence[float], cutoff_hz: float, beside_off_line: bool = False
) -> str:
    """Return the verdict of the noise evidence (see the module docstring).

    Parameters
    ----------
    evidence : float
        2 (log L_platform - log L_sensor) over every run.
    per_run : sequence of float
        The same, of each run alone.
    cutoff_hz : float
        The sensor filter's cut-off.
    beside_off_line : bool
        Whether an effect with off-line power of its own (:data:`OFF_LINE_EFFECTS`) is named
        with it.

    Examples
    --------
    >>> side_verdict(-700.0, [-500.0, -200.0], 2.0)
    'sensor'
    >>> side_verdict(2400.0, [-750.0, -460.0, 3610.0], 2.0)  # the runs disagree
    'undecided'
    >>> side_verdict(-700.0, [-500.0, -200.0], 20.0)  # less than an octave below 30 Hz
    'undecided'

    """
    if SIDE_BAND_HZ < 2.0 * cutoff_hz:
        return "undecided"  # less than an octave of filtered noise in the band
    if beside_off_line:
        return "undecided"  # off-line power of its own, read as unfiltered noise
    if max(per_run, default=0.0) > BIC_MARGIN and min(per_run, default=0.0) < -BIC_MARGIN:
        return "undecided"  # the runs disagree: one's off-line power is not the IMU's noise
    return "platform" if evidence > BIC_MARGIN else "sensor" if evidence < -BIC_MARGIN else (
        "undecided")  # fmt: skip


def rule_out_by_noise(
    model: Model, findings: list[Finding], imu_noise: float | None = None
) -> list[Finding]:
    """Take out of each ambiguous finding's alternatives those the noise rules out.

    Only where the finding's ``side`` verdict is ``sensor`` (the measurement's noise is filtered
    as the named sensor filter says): each alternative without a ``sensor_filter`` (and
    without an effect of :data:`OFF_LINE_EFFECTS`, whose own off-line power the noise cannot
    tell from the sensor's) is scored on the same noise as the named model, its own
    ``2 (log L_named - log L_alternative)``; past the margin, with no run past it the other
    way, it is moved to the evidence's ``ruled_out_by_noise`` with that figure. A finding whose
    alternatives all go is no longer ambiguous. Where the alternatives listed reached
    :data:`twin.diagnose.select.MAX_ALTERNATIVES` (others may not have been weighed), nothing
    is taken out.

    Parameters
    ----------
    model : Model
        The DOF's fitted model (the named extensions), as :func:`judge_side` weighed it.
    findings : list of Finding
        The DOF's findings, each with its ``side`` judgement.
    imu_noise : float, optional
        The IMU's noise over its data sheet's when known (else fitted for each model).

    """
    known = None if imu_noise is None else float(imu_noise) ** 2
    segments: list | None = None
    out = []
    for f in findings:
        side = f.evidence.get("side")
        alts: list[dict] = f.evidence.get("alternatives") or []  # type: ignore[assignment]
        if (not f.ambiguous or not alts or len(alts) >= MAX_ALTERNATIVES
                or not isinstance(side, dict) or side["verdict"] != "sensor"):  # fmt: skip
            out.append(f)
            continue
        kept, gone = [], []
        for a in alts:
            if "sensor_filter" in a["effects"] or set(a["effects"]) & set(OFF_LINE_EFFECTS):
                kept.append(a)
                continue
            if segments is None:
                segments = [segment(c, max_hz=SIDE_BAND_HZ) for c in model.case.of(model.dof)]
            exts = [make_extension(e, list(a["parameters"][e]), list(a["parameters"][e].values()),
                                   model.dof) for e in a["effects"]]  # fmt: skip
            other = Model(model.case, model.dof, exts, None, model._cache)
            against, per_run = noise_evidence(model, other, segments, known)
            if against > BIC_MARGIN and min(per_run) > -BIC_MARGIN:
                gone.append(a | {"noise_evidence_against": float(against)})
            else:
                kept.append(a)
        if not gone:
            out.append(f)
            continue
        evidence = {**f.evidence, "alternatives": kept, "ambiguous": bool(kept),
                    "ruled_out_by_noise": gone}  # fmt: skip
        out.append(replace(f, evidence=evidence))
    return out


def ruled_out_text(f: Finding) -> str | None:
    """Return the alternatives the noise ruled out beside a finding, in words (None: none)."""
    gone = f.evidence.get("ruled_out_by_noise") or []
    if not gone:
        return None
    parts = "; ".join(
        f"{describe_alternative(a)}, noise evidence {a['noise_evidence_against']:.0f} against it"
        for a in gone  # type: ignore[union-attr]
    )
    return (
        "ruled out by the noise (the sensor's noise is filtered as the named cut-off says, which "
        "no effect outside the sensor explains): " + parts
    )


def decide_side(
    model: Model, findings: list[Finding], imu_noise: float | None = None
) -> tuple[Model, list[Finding]]:
    """Apply :func:`judge_side` to a DOF's findings: the platform reading replaces the sensor's.

    Every finding of the named set carries the judgement in its evidence (``side``).
    """
    side = judge_side(model, imu_noise)
    if side is None:
        return model, findings
    out = []
    for f in findings:
        evidence = {**f.evidence, "side": side.to_json()}
        ext = side.platform if (f.extension is side.sensor and side.verdict == "platform") \
            else f.extension  # fmt: skip
        out.append(replace(f, extension=ext, evidence=evidence))
    if side.verdict != "platform":
        return model, out
    exts = [side.platform if e is side.sensor else e for e in model.extensions]
    return Model(model.case, model.dof, exts, model.anchor, model._cache), out
