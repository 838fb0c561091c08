"""Table 5.5 and the integration step: how much of the full model's extra lag is the 1 ms step.

The full MPI model's own first-order lag per DOF (§5.5.1, ``twin dynamics mpi``) comes out
6-15 % above Table 5.5. This fits it again with the physics stepped at 1, 0.5 and 0.25 ms (the
loop-closure constraints' time constant following the step, two steps, as the builder sets
it) and prints t_m per DOF beside the thesis: what changes with the step is the integration's
share, what stays is the model's.
"""

import time

from twin.agard.compare import platform_dynamics
from twin.core.thesis import TABLE_5_5


def main() -> None:
    dofs = ("surge", "heave", "pitch")
    rows = {}
    for step in (1e-3, 5e-4, 2.5e-4):
        t0 = time.perf_counter()
        dyn = platform_dynamics("mpi", dofs=dofs, timestep_s=step)
        rows[step] = {d: dyn.fits[d].t_m * 1e3 for d in dofs}
        print(f"  step {step * 1e3:.2f} ms: {time.perf_counter() - t0:.0f} s", flush=True)
    print("t_m [ms] per DOF (Table 5.5) against the integration step:")
    print(f"{'step':>8s} " + " ".join(f"{d:>14s}" for d in dofs))
    for step, v in rows.items():
        cells = " ".join(
            f"{v[d]:6.2f} ({100 * (v[d] / (1e3 * TABLE_5_5[d][0]) - 1):+4.0f} %)" for d in dofs
        )
        print(f"{step * 1e3:6.2f}ms {cells}")
    print(f"{'thesis':>8s} " + " ".join(f"{1e3 * TABLE_5_5[d][0]:14.2f}" for d in dofs))


if __name__ == "__main__":
    main()
