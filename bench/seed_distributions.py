"""Reproductions that depend on the seed, as distributions over seeds (median, 5-95 %).

A figure that depends on the noise's seed is a distribution; one seed matching the thesis is
not a reproduction. For 20 seeds (``--seeds``) on the reduced model (``--model full`` for the
MuJoCo one), :mod:`twin.agard.seed_spread`:

* Table 5.6: the delay fitted with equal weights behind the 1 Hz filter (SRS + MPI filter,
  25 ms), heave and pitch (thesis 12.0 and 14.2 ms), and the SNR-weighted fit (25 ms
  configured);
* §3.4.4: the dynamic threshold's tau (1 Hz filter, 100 ms fixed, 0.1 m/s^2 steps of 1 s in
  surge; thesis about 300 ms).
"""

import argparse

from twin.agard.seed_spread import table_5_6_delays, threshold_taus


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--model", default="reduced", choices=("reduced", "full"))
    args = parser.parse_args()
    print(f"{args.model} model, {args.seeds} seeds:")
    for spread in (
        *table_5_6_delays(args.seeds, args.model),
        threshold_taus(args.seeds, args.model),
    ):
        inside = spread.contains_thesis()
        note = "" if inside is None else ("; thesis inside" if inside else "; thesis OUTSIDE")
        print(f"  {spread.format()}{note}")


if __name__ == "__main__":
    main()
