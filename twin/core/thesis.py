"""Reference numbers printed in the thesis (Nieuwenhuizen 2012), for reports and tests.

Only numbers read from the thesis' tables live here; nothing in this module is computed.
"""

from __future__ import annotations

from types import MappingProxyType

#: Table 5.1 (= Tables B.1, B.3): workspace per DOF. Translations are total ranges [mm];
#: rotations are (min, max) [deg] about neutral.
TABLE_5_1 = MappingProxyType(
    {
        "mpi": MappingProxyType(
            {
                "surge": 922.0,
                "sway": 848.0,
                "heave": 500.0,
                "roll": (-26.6, 26.6),
                "pitch": (-25.1, 24.1),
                "yaw": (-43.5, 43.5),
            }
        ),
        "srs": MappingProxyType(
            {
                "surge": 2240.0,
                "sway": 2062.0,
                "heave": 1314.0,
                "roll": (-25.9, 25.9),
                "pitch": (-23.7, 24.3),
                "yaw": (-41.6, 41.6),
            }
        ),
    }
)


def table_5_1_targets(platform: str) -> dict[str, float]:
    """Table 5.1 as flat comparable figures: spans [mm] and rotation limits [deg].

    Keys are ``surge, sway, heave`` (total range, mm) and ``roll_min, roll_max, pitch_min,
    pitch_max, yaw_min, yaw_max`` (deg).
    """
    table = TABLE_5_1[platform]
    out: dict[str, float] = {}
    for dof, value in table.items():
        if isinstance(value, tuple):
            out[f"{dof}_min"], out[f"{dof}_max"] = value
        else:
            out[dof] = value
    return out


#: Table 5.2: multi-sine describing-function signals. Per signal: frequencies [Hz],
#: translational amplitudes [m/s^2] and rotational amplitudes [deg/s^2], all in acceleration.
TABLE_5_2 = MappingProxyType(
    {
        1: MappingProxyType(
            {
                "frequency_hz": (0.10, 0.25, 0.65, 0.85, 3.35),
                "translation_m_s2": (0.009, 0.047, 0.123, 0.160, 0.200),
                "rotation_deg_s2": (0.974, 5.329, 13.866, 18.163, 57.296),
            }
        ),
        2: MappingProxyType(
            {
                "frequency_hz": (0.20, 0.45, 1.35, 2.30, 5.50, 7.10),
                "translation_m_s2": (0.035, 0.085, 0.200, 0.200, 0.200, 0.200),
                "rotation_deg_s2": (3.953, 9.626, 27.789, 46.983, 57.296, 57.296),
            }
        ),
    }
)

#: Table 5.5: first-order time constant t_m [s] and break frequency f_m [Hz] fitted to the
#: describing functions of the full MPI model (no platform filter), per DOF.
TABLE_5_5 = MappingProxyType(
    {
        "surge": (0.00560, 28.42),
        "sway": (0.00561, 28.37),
        "heave": (0.00081, 196.49),
        "roll": (0.01243, 12.80),
        "pitch": (0.01242, 12.81),
        "yaw": (0.01398, 11.38),
    }
)

#: Table 6.3: the eight experimental conditions: (platform filter break frequency [Hz] or
#: None, total motion-system time delay [s], MPI noise model on).
TABLE_6_3 = MappingProxyType(
    {
        1: (None, 0.025, False),
        2: (None, 0.025, True),
        3: (None, 0.035, False),
        4: (None, 0.035, True),
        5: (1.0, 0.025, False),
        6: (1.0, 0.025, True),
        7: (1.0, 0.035, False),
        8: (1.0, 0.035, True),
    }
)

#: Eq 5.10: heave motion-noise shaping filter, gain and time constants [s]:
#: 0.084 (1 + 0.022 s) / ((1 + 0.009 s)(1 + 0.008 s)).
EQ_5_10 = MappingProxyType({"gain": 0.084, "zero_s": 0.022, "poles_s": (0.009, 0.008)})

#: §5.4.4: standard deviation of Eq 5.10 applied to unit-variance white noise [m/s^2].
NOISE_SIGMA = 4.230e-2

#: Eq 5.12 and 5.13: SRS resonance terms H = 1 + T s, T [s], per DOF (heave, pitch).
EQ_5_12_13 = MappingProxyType({"heave": 0.023, "pitch": 0.027})

#: Table 5.6, MPI IMU: time delays [ms] fitted on the SRS, heave and pitch, for the baseline
#: and the MPI model's 1, 5, 10 Hz filters, with tau = 0 and 35 ms: (tau=0, tau=35, delta).
TABLE_5_6_MPI_IMU = MappingProxyType(
    {
        "heave": {None: (24.0, 60.0, 36.0), 1.0: (12.0, 48.4, 36.4), 5.0: (19.0, 53.4, 34.4),
                  10.0: (19.3, 53.7, 34.4)},
        "pitch": {None: (22.9, 58.5, 35.6), 1.0: (14.2, 51.6, 37.4), 5.0: (18.0, 52.1, 34.1),
                  10.0: (17.5, 53.3, 35.8)},
    }
)  # fmt: skip

#: §3.4.3-3.4.4 and §4.3: figures read off the thesis' plots: fitted delays [ms], the dynamic
#: threshold's tau [ms] (1 Hz filter, 0.1 m/s^2 steps of 1 s) and the 63 % times [ms] with the
#: 1, 5, 10 Hz filters (0.1875 m/s^2 steps of 0.5 s).
CHAPTER_3_4 = MappingProxyType(
    {"delay_2008_ms": 100.0, "threshold_tau_ms": 300.0, "delay_ms": 35.0,
     "t63_ms": MappingProxyType({1.0: 350.0, 5.0: 100.0, 10.0: 50.0})}
)  # fmt: skip

#: Table 2.3: mean absolute error of the estimated parameters over 10,000 runs, (FC, ARX).
TABLE_2_3 = MappingProxyType(
    {"k_v": (8.98e-2, 5.84e-2), "tau_lead": (2.44, 1.05), "tau_v": (1.38e-2, 8.44e-3),
     "k_m": (2.71e-1, 9.64e-2), "tau_m": (1.38e-2, 8.31e-3), "zeta_nm": (5.87e-2, 2.76e-2),
     "omega_nm": (6.56e-1, 4.62e-1)}
)  # fmt: skip

#: Tables 6.4-6.7: main effects of the repeated-measures ANOVA (df 1, 8) on the Chapter 6
#: measures: measure -> factor -> (F, direction of the mean with the factor's second level
#: minus its first: "+", "-", or None where not significant and no direction is stated).
#: Directions from §6.4: with the 1 Hz filter var(e) rose, var(u) fell slightly, both
#: crossovers fell, both phase margins rose, K_v and K_m fell, t_lead and t_lag rose, the
#: neuromuscular frequency fell and its damping fell slightly.
TABLES_6_4_TO_6_7 = MappingProxyType(
    {
        "var_e": {"filter": (357.79, "+"), "delay": (0.39, None), "noise": (3.23, None)},
        "var_u": {"filter": (15.00, "-"), "delay": (2.74, None), "noise": (0.18, None)},
        "crossover_disturbance_rad_s": {"filter": (159.68, "-"), "delay": (1.34, None),
                                        "noise": (0.00, None)},
        "crossover_target_rad_s": {"filter": (5.98, "-"), "delay": (1.24, None),
                                   "noise": (0.45, None)},
        "phase_margin_disturbance_deg": {"filter": (68.95, "+"), "delay": (1.17, None),
                                         "noise": (0.54, None)},
        "phase_margin_target_deg": {"filter": (27.05, "+"), "delay": (0.17, None),
                                    "noise": (0.21, None)},
        "k_v": {"filter": (43.36, "-"), "delay": (3.82, None), "noise": (0.44, None)},
        "k_m": {"filter": (66.20, "-"), "delay": (4.67, None), "noise": (0.36, None)},
        "t_lead": {"filter": (60.96, "+"), "delay": (1.42, None), "noise": (0.13, None)},
        "t_lag": {"filter": (132.26, "+"), "delay": (2.22, None), "noise": (0.55, None)},
        # Table 6.7 (tau_v is compared where the subjects adapt it; tau_m, "close to zero"
        # with K_m behind the filter, where the pilot model is identified from the runs,
        # twin.pilot.studies.identified: a subject who does not use motion has no tau_m of its own)
        "omega_nm": {"filter": (53.11, "-"), "delay": (0.00, None), "noise": (0.14, None)},
        "zeta_nm": {"filter": (6.86, "-"), "delay": (0.34, None), "noise": (0.05, None)},
        "tau_v": {"filter": (35.80, "-"), "delay": (1.50, None), "noise": (0.75, None)},
        "tau_m": {"filter": (140.10, "-"), "delay": (0.08, None), "noise": (1.55, None)},
    }
)  # fmt: skip
