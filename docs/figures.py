"""Generate every figure of the documentation, and execute the notebooks for it.

``make docs`` runs this before Sphinx. Each figure is made by the twin's own commands (the
ones the pages show) or library functions, into ``docs/_figures/``; the notebooks of
``notebooks/`` are executed into ``docs/notebooks/`` (their outputs are rendered as stored:
``nb_execution_mode = "off"``). Nothing here is pasted: delete ``docs/_figures/`` and it all
comes back.

A figure is made again when it is missing or when the twin's code or models changed since it
was made (a digest of ``twin/``, ``models/`` and of the function that makes it; a notebook
when it or they changed); ``--force`` makes all of them again. All of them: about 10 min on
two idle cores, most of it the Chapter 6 populations; the notebooks about 8 min more.

    python docs/figures.py [--force] [--only NAME ...] [--no-notebooks] [--list]
"""

from __future__ import annotations

import argparse
import hashlib
import inspect
import json
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
OUT = DOCS / "_figures"
WORK = OUT / "work"
DIGESTS = OUT / "digests.json"
NOTEBOOKS = DOCS / "notebooks"
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(ROOT))


def _env() -> dict[str, str]:
    """Return the environment of the commands: this checkout's twin first."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env.setdefault("MPLBACKEND", "Agg")
    return env


def twin(*args: str, cwd: Path = WORK) -> str:
    """Run ``twin ARGS`` (this checkout's) in ``cwd``; return its stdout."""
    cmd = [sys.executable, "-m", "twin.cli", *args]
    done = subprocess.run(cmd, cwd=cwd, env=_env(), capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"twin {' '.join(args)}: exit {done.returncode}\n{done.stderr}")
    return done.stdout


def _keep(src: Path, name: str) -> Path:
    """Copy a figure a command wrote to docs/_figures/NAME."""
    dst = OUT / name
    shutil.copyfile(src, dst)
    return dst


# -- the figures: each function makes the files it names -------------------------------------


def demo() -> None:
    """``make demo``'s Table 5.2 sweep (MPI full and reduced, SRS), its diagnosis, ``design``."""
    twin("agard", "demo", "--out", "demo", "--quiet", "--overwrite")
    _keep(WORK / "demo" / "df-pitch.png", "demo-df-pitch.png")
    _keep(WORK / "demo" / "df-heave.png", "demo-df-heave.png")
    runs = []
    for n in (1, 2):
        run = f"demo/recorded-pitch-{n}"
        twin(
            "simulate",
            str(ROOT / "notebooks/data/srs-imu-filtered.json"),
            "--quiet",
            "--signal",
            f"multisine{n}-pitch",
            "--model",
            "reduced",
            "--seed",
            str(n),
            "--overwrite",
            "--out",
            run,
        )
        runs.append(run)
    twin("diagnose", *runs, "--config", "srs", "--out", "demo/diagnosis", "--quiet", "--overwrite")
    _keep(WORK / "demo/diagnosis/df_pitch.png", "diagnosis-df_pitch.png")
    _keep(WORK / "demo/diagnosis/residual_pitch.png", "diagnosis-residual_pitch.png")


def compare() -> None:
    """Full against reduced MPI model (§5.5), as the configurations guide shows it."""
    twin(
        "compare",
        "mpi",
        "--dof",
        "heave",
        "--dof",
        "pitch",
        "--plot",
        "mpi.png",
        "--quiet",
        "--overwrite",
    )
    _keep(WORK / "mpi.png", "compare-mpi.png")


def chapter_3() -> None:
    """Ch 3: the 2008 MPI software (1 Hz, 100 ms): DF, noise, SNR, threshold, parasitic."""
    for test, name, extra in (
        ("df", "ch3-df-pitch", ["--dof", "pitch"]),
        ("noise", "ch3-noise-heave", ["--dof", "heave", "--model", "reduced"]),
        ("snr", "ch3-snr-heave", ["--dof", "heave", "--model", "reduced"]),
        ("threshold", "ch3-threshold-heave", ["--dof", "heave", "--fix-delay-ms", "100"]),
    ):
        folder = WORK / name
        twin("agard", test, "mpi-2008", *extra, "--out", name, "--quiet", "--overwrite")
        _keep(_only_png(folder), f"{name}.png")
    twin(
        "agard",
        "parasitic",
        "srs",
        "--model",
        "reduced",
        "--out",
        "parasitic",
        "--quiet",
        "--overwrite",
    )
    _keep(_only_png(WORK / "parasitic"), "parasitic-srs.png")


def chapter_4() -> None:
    """Ch 4: the dynamic threshold behind the 1, 5 and 10 Hz filters (35 ms)."""
    for hz in ("1", "5", "10"):
        name = f"ch4-threshold-{hz}hz"
        twin(
            "agard",
            "threshold",
            "mpi",
            "--dof",
            "heave",
            "--break-hz",
            hz,
            "--amplitude",
            "0.1875",
            "--step-s",
            "0.5",
            "--out",
            name,
            "--quiet",
            "--overwrite",
        )
        _keep(_only_png(WORK / name), f"{name}.png")


def omct() -> None:
    """§5.6.3, Fig 5.12: SRS baseline and the MPI model's 1, 5, 10 Hz filters on the SRS."""
    from twin.agard.omct import plot_omct, read_bounds, run_omct
    from twin.agard.session import Session
    from twin.chain.simulate import default_imu
    from twin.measurement.measure import Bench, configure

    imu = default_imu("srs").ideal()
    results = []
    for fb in (0.0, 1.0, 5.0, 10.0):
        delay = 25.0 if fb == 0.0 else 60.0
        bench = Bench(
            configure("srs", break_hz=fb, delay_ms=delay, noise=False), "reduced", imu=imu
        )
        with Session(bench) as s:
            label = "SRS baseline" if fb == 0 else f"MPI {fb:g} Hz"
            results.append(run_omct(s, "pitch", label=label))
    plot_omct(results, read_bounds(), path=str(OUT / "omct-fig-5-12.png"))


def chapter_2() -> None:
    """Ch 2: FC against ARX over 1000 closed-loop runs (§2.5)."""
    from twin.pilot.studies.montecarlo import monte_carlo

    monte_carlo(runs=1000, seed=0).plot(path=str(OUT / "ch2-montecarlo.png"))


def chapter_6_fixed() -> None:
    """Ch 6: the eight conditions flown by one fixed pilot (Fig 6.5-6.9)."""
    twin("pilot", "experiment", "fixed", "--runs", "5", "--plot", "conditions.png", "--quiet",
         "--overwrite")  # fmt: skip
    _keep(WORK / "conditions.png", "ch6-conditions.png")


def _adaptive(stem: str, second: str, *options: str) -> None:
    """Fly adaptive subjects (``pilot experiment subjects``); keep its two figures."""
    twin("pilot", "experiment", "subjects", *options, "--plot", f"{stem}.png",
         "--quiet", "--overwrite")  # fmt: skip
    _keep(WORK / f"{stem}.png", f"ch6-{stem}.png")
    _keep(WORK / f"{stem}-{second}.png", f"ch6-{stem}-{second}.png")


def chapter_6_adaptive() -> None:
    """Ch 6: nine adaptive subjects and the thesis' ANOVA."""
    _adaptive("anova", "conditions")


def chapter_6_replication() -> None:
    """Ch 6: five populations of eight subjects (the pages' tables: 20 of nine)."""
    _adaptive("replication", "subjects", "--populations", "5", "--subjects", "8")


def sweep() -> None:
    """Sweep the MPI's describing function over three filters (a small grid)."""
    (WORK / "grid.toml").write_text(
        'task = "df"\nconfig = "mpi"\nmodel = "reduced"\n\n[grid]\n'
        'break_hz = [0.5, 1.0, 2.0]\ndof = ["pitch"]\n'
    )
    twin("sweep", "grid.toml", "--out", "sweep", "--scheduler", "inline", "--quiet", "--overwrite")
    _keep(WORK / "sweep" / "sweep.png", "sweep.png")


def _only_png(folder: Path) -> Path:
    """Return the one figure a test's ``--out`` folder holds."""
    pngs = sorted(folder.glob("*.png"))
    if len(pngs) != 1:
        raise RuntimeError(f"{folder}: expected one figure, found {[p.name for p in pngs]}")
    return pngs[0]


#: name -> (what makes it, the files it makes in docs/_figures/)
FIGURES: dict[str, tuple[Callable[[], None], tuple[str, ...]]] = {
    "demo": (
        demo,
        (
            "demo-df-pitch.png",
            "demo-df-heave.png",
            "diagnosis-df_pitch.png",
            "diagnosis-residual_pitch.png",
        ),
    ),
    "compare": (compare, ("compare-mpi.png",)),
    "chapter-2": (chapter_2, ("ch2-montecarlo.png",)),
    "chapter-3": (
        chapter_3,
        (
            "ch3-df-pitch.png",
            "ch3-noise-heave.png",
            "ch3-snr-heave.png",
            "ch3-threshold-heave.png",
            "parasitic-srs.png",
        ),
    ),
    "chapter-4": (
        chapter_4,
        ("ch4-threshold-1hz.png", "ch4-threshold-5hz.png", "ch4-threshold-10hz.png"),
    ),
    "omct": (omct, ("omct-fig-5-12.png",)),
    "chapter-6-fixed": (chapter_6_fixed, ("ch6-conditions.png",)),
    "chapter-6-adaptive": (chapter_6_adaptive, ("ch6-anova.png", "ch6-anova-conditions.png")),
    "chapter-6-replication": (
        chapter_6_replication,
        ("ch6-replication.png", "ch6-replication-subjects.png"),
    ),
    "sweep": (sweep, ("sweep.png",)),
}


def source_digest() -> str:
    """SHA-256 over the code and models the figures come from (a notebook adds its own)."""
    h = hashlib.sha256()
    files = []
    for folder, pattern in (
        ("twin", "*.py"),
        ("twin", "*.toml"),
        ("models", "*"),
    ):
        files += sorted(
            p
            for p in (ROOT / folder).rglob(pattern)
            if p.is_file() and "__pycache__" not in p.parts
        )
    for p in files:
        h.update(str(p.relative_to(ROOT)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def execute_notebooks(digest: str, force: bool) -> None:
    """Execute each notebook into docs/notebooks/ (skipped when its copy is current)."""
    import nbclient
    import nbformat
    from twin_docs import notebook_digest, stamp_of

    NOTEBOOKS.mkdir(exist_ok=True)
    run_dir = WORK / "notebooks"
    if run_dir.exists():
        shutil.rmtree(run_dir)
    shutil.copytree(ROOT / "notebooks", run_dir)
    for src in sorted((ROOT / "notebooks").glob("*.ipynb")):
        dst = NOTEBOOKS / src.name
        stamp = stamp_of(dst)
        mark = f"{notebook_digest(src)}"
        if (
            not force
            and dst.is_file()
            and stamp.is_file()
            and stamp.read_text() == mark
            and _made_with(f"notebook:{src.name}") == digest
        ):
            continue
        t0 = time.time()
        nb = nbformat.read(src, as_version=4)
        os.environ.update(_env())
        os.environ.pop("MPLBACKEND", None)  # the kernel's own, inline: figures as outputs
        client = nbclient.NotebookClient(
            nb, timeout=1800, kernel_name="python3", resources={"metadata": {"path": str(run_dir)}}
        )
        client.execute()
        nbformat.write(nb, dst)
        stamp.write_text(mark)
        _record(f"notebook:{src.name}", digest)
        print(f"notebook {src.name}: {time.time() - t0:.0f} s", flush=True)


def _made_with(key: str) -> str | None:
    return json.loads(DIGESTS.read_text()).get(key) if DIGESTS.is_file() else None


def _record(key: str, digest: str) -> None:
    known = json.loads(DIGESTS.read_text()) if DIGESTS.is_file() else {}
    known[key] = digest
    DIGESTS.write_text(json.dumps(known, indent=1, sort_keys=True))


def main(argv: list[str] | None = None) -> int:
    """Make the figures that are missing or stale (all with ``--force``), then the notebooks."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--force", action="store_true", help="make every figure again")
    ap.add_argument("--only", nargs="+", choices=sorted(FIGURES), help="these figures only")
    ap.add_argument("--no-notebooks", action="store_true", help="do not execute the notebooks")
    ap.add_argument("--list", action="store_true", help="list the figures and their files")
    args = ap.parse_args(argv)
    if args.list:
        for name, (_, files) in FIGURES.items():
            print(f"{name}: {', '.join(files)}")
        return 0
    OUT.mkdir(exist_ok=True)
    if WORK.exists():  # the commands' outputs of an earlier build: each figure starts afresh
        shutil.rmtree(WORK)
    WORK.mkdir()
    digest = source_digest()
    for name in args.only or FIGURES:
        make, files = FIGURES[name]
        made_by = hashlib.sha256((digest + inspect.getsource(make)).encode()).hexdigest()
        current = all((OUT / f).is_file() for f in files) and _made_with(name) == made_by
        if current and not args.force:
            continue
        t0 = time.time()
        make()
        missing = [f for f in files if not (OUT / f).is_file()]
        if missing:
            raise RuntimeError(f"{name} did not make {missing}")
        _record(name, made_by)
        print(f"{name}: {', '.join(files)} ({time.time() - t0:.0f} s)", flush=True)
    if not args.no_notebooks and not args.only:
        execute_notebooks(digest, args.force)
    return 0


if __name__ == "__main__":
    sys.exit(main())
