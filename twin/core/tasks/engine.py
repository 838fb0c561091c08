"""Where a batch of tasks runs: this process, a local Dask cluster, or a running scheduler.

Every batch command of the twin (``pilot montecarlo``, ``pilot experiment``, ``sweep``,
``diagnose --each``) splits its work into **tasks that are pure functions of their inputs**
(configuration, signal, seed: a task draws its randomness from its own seed only) and hands
them to an :class:`Engine`. So the results are bit-identical whatever runs them: one process,
two local workers or a hundred remote ones, in any order. Results stream back as tasks finish
(progress counts them); a task that fails is reported with its inputs (:mod:`.outcome`) and
the others' results are kept. A worker that dies mid-task (killed, out of memory) costs
nothing but time: the Dask scheduler runs its tasks again elsewhere (up to
``distributed.scheduler.allowed-failures`` times, 3 by default).

The ``--scheduler`` option of those commands (default: the ``TWIN_SCHEDULER`` environment
variable, else ``local``) says where:

===================  ========================================================================
value                where
===================  ========================================================================
``local``            a Dask ``LocalCluster`` started for the command: one worker process per
                     CPU core, one thread each (BLAS pinned to one thread per worker, as the
                     Dask nanny does by default: no oversubscribed cores); without Dask
                     installed (the core install: ``pip install twin``, not
                     ``twin[cluster]``), a pool of as many worker processes of the standard
                     library (:class:`concurrent.futures.ProcessPoolExecutor`), set up alike
``local:N``          the same with N worker processes
``inline``           this process, one task after another (no Dask)
``tcp://HOST:PORT``  a running ``dask scheduler`` (``HOST:PORT`` alone means tcp); its
                     workers need the same twin version installed (checked on connect)
===================  ========================================================================

The results are the same bits either way. What only Dask gives: a worker that dies mid-task
(killed, out of memory) has its tasks run again elsewhere; in the standard library's pool
the batch's unfinished tasks are reported as failed instead. Remote schedulers need Dask.

A local cluster is started only when a batch has more than one task, so a one-task command
pays nothing for it. Its workers ignore Ctrl-C: this process shuts them down
(:mod:`twin.core.interrupts`). A scheduler address must answer within seconds: what answers
instead (nothing, an HTTP server, a silent port) is named at once
(:mod:`.scheduler_probe`).

Examples
--------
>>> with Engine("inline") as engine:
...     engine.map(pow, [(2, 3), (3, 2)], [{"base": 2}, {"base": 3}], "powers").values()
[8, 9]

"""

from __future__ import annotations

import asyncio
import difflib
import importlib.util
import logging
import multiprocessing
import os
import re
import traceback
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from multiprocessing import resource_tracker
from typing import Any, Self

from twin.core.errors import TwinError, UsageError
from twin.core.interrupts import deferred
from twin.core.progress import ProgressFn
from twin.core.tasks.outcome import Failure, Outcome
from twin.core.tasks.scheduler_probe import HANDSHAKE_TIMEOUT_S, what_answers
from twin.core.tasks.worker_setup import process_setup
from twin.core.threads import single_blas_thread

#: Environment variable holding the default ``--scheduler``.
SCHEDULER_ENV = "TWIN_SCHEDULER"
#: ``--scheduler`` when neither the option nor the environment variable is given.
DEFAULT_SCHEDULER = "local"
#: Most worker processes ``local:N`` starts.
MAX_LOCAL_WORKERS = 256
#: How long to wait for a remote scheduler to have a worker, once it answered [s] (it must
#: answer within :data:`~twin.core.tasks.scheduler_probe.HANDSHAKE_TIMEOUT_S`).
CONNECT_TIMEOUT_S = 20.0
#: The preload of a local cluster's worker processes (Ctrl-C ignored).
WORKER_SETUP = "twin.core.tasks.worker_setup"
#: How long the workers of an abandoned batch get to stop before they are killed [s].
STOP_S = 0.5
SCHEDULER_HELP = (
    "where tasks run: 'local' (one worker process per core, the default: a Dask cluster with "
    "the cluster extra, else a process pool), 'local:N' (N workers), 'inline' (this process) "
    f"or a running Dask scheduler's address (tcp://HOST:PORT); default: ${SCHEDULER_ENV} or "
    "'local'"
)


#: What installs Dask (the ``cluster`` extra of the package).
CLUSTER_INSTALL = "pip install 'twin[cluster]'"


def dask_installed() -> bool:
    """Whether Dask's ``distributed`` is installed (the ``cluster`` extra)."""
    return importlib.util.find_spec("distributed") is not None


class SchedulerError(TwinError, ConnectionError):
    """A scheduler that cannot be reached or used (no workers, other twin version)."""


@dataclass(frozen=True)
class SchedulerSpec:
    """A parsed ``--scheduler``.

    Attributes
    ----------
    kind : str
        ``"inline"``, ``"local"`` or ``"remote"``.
    workers : int or None
        Worker processes of a local cluster (None: one per CPU core).
    address : str or None
        The remote scheduler's address.

    """

    kind: str
    workers: int | None = None
    address: str | None = None

    @property
    def on_this_machine(self) -> bool:
        """Whether tasks run on this machine (inline or a local cluster): they see its files."""
        return self.kind != "remote"

    def describe(self) -> str:
        """Say where tasks run, e.g. ``local cluster (2 worker processes)``."""
        if self.kind == "inline":
            return "this process"
        if self.kind == "local":
            kind = "local Dask cluster" if dask_installed() else "local process pool"
            return f"{kind} ({self.workers or cpu_count()} worker processes)"
        return f"Dask scheduler {self.address}"


def cpu_count() -> int:
    """CPU cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


_ADDRESS = re.compile(r"^(?:(tcp|tls|ws|wss|inproc|ucx)://)?[\w.\-\[\]:]+:\d+$")


def parse_scheduler(text: str | None) -> SchedulerSpec:
    """Parse a ``--scheduler`` value (None: ``$TWIN_SCHEDULER`` or ``local``).

    Raises
    ------
    UsageError
        For anything but ``local``, ``local:N`` (N >= 1), ``inline`` or ``[proto://]host:port``.

    Examples
    --------
    >>> parse_scheduler("local:2")
    SchedulerSpec(kind='local', workers=2, address=None)
    >>> parse_scheduler("10.0.0.5:8786").address
    'tcp://10.0.0.5:8786'

    """
    raw = text if text is not None else os.environ.get(SCHEDULER_ENV) or DEFAULT_SCHEDULER
    value = raw.strip()
    source = "--scheduler" if text is not None else f"${SCHEDULER_ENV}"
    if value == "inline":
        return SchedulerSpec("inline")
    if value == "local":
        return SchedulerSpec("local")
    if value.startswith("local:"):
        n = value.removeprefix("local:")
        if not re.fullmatch(r"[0-9]{1,4}", n) or not 1 <= int(n) <= MAX_LOCAL_WORKERS:
            raise UsageError(f"{source} local:N needs a worker count 1 <= N <= "
                             f"{MAX_LOCAL_WORKERS}; got {raw!r}")  # fmt: skip
        return SchedulerSpec("local", workers=int(n))
    host = value.split("://")[-1].rsplit(":", 1)[0]
    near = difflib.get_close_matches(host, ["local", "inline"], cutoff=0.6)
    if _ADDRESS.match(value) and near and host not in ("localhost", "127.0.0.1"):
        raise UsageError(f"{source} {raw!r} looks like a misspelt 'local:N' or 'inline'; "
                         "a scheduler address is tcp://HOST:PORT")  # fmt: skip
    if _ADDRESS.match(value) and 1 <= int(value.rsplit(":", 1)[1]) <= 65535:
        return SchedulerSpec("remote", address=value if "://" in value else f"tcp://{value}")
    raise UsageError(
        f"{source} must be 'local', 'local:N', 'inline' or a scheduler address such as "
        f"tcp://HOST:8786; got {raw!r}"
    )


def _failure(i: int, inputs: Mapping[str, Any], e: BaseException, tb: Any) -> Failure:
    """Return a failed task's record: the same text whether it ran here or on a worker."""
    from concurrent.futures import CancelledError

    error = "cancelled" if isinstance(e, CancelledError) else f"{type(e).__name__}: {e}"
    text = "".join(traceback.format_exception(type(e), e, tb)) if tb is not None else ""
    return Failure(i, dict(inputs), error, text)


def _twin_version() -> str:
    from importlib.metadata import version

    return version("twin")


class Engine:
    """Runs batches of tasks (see the module docstring); a context manager.

    Parameters
    ----------
    scheduler : str or SchedulerSpec, optional
        Where tasks run (``--scheduler``; None: ``$TWIN_SCHEDULER`` or ``local``).

    """

    def __init__(self, scheduler: str | SchedulerSpec | None = None) -> None:
        given = isinstance(scheduler, SchedulerSpec)
        self.spec = scheduler if given else parse_scheduler(scheduler)  # type: ignore[arg-type]
        self._client: Any = None
        self._cluster: Any = None

    def __enter__(self) -> Self:
        """Enter the context; a remote scheduler is reached (or refused) now.

        So a command given an unreachable ``--scheduler`` says so before its own set-up, not
        after it; a local cluster still starts at the first :meth:`map`.
        """
        if self.spec.kind == "remote":
            self.client()
        return self

    def __exit__(self, *exc: object) -> None:
        """Close the client and any cluster this engine started."""
        self.close()

    def close(self) -> None:
        """Close the client and any cluster this engine started.

        A Ctrl-C meanwhile waits until they are closed (:func:`twin.core.interrupts.deferred`):
        a cluster closed halfway is closed again at exit, with a traceback.
        """
        with deferred():
            if self._client is not None:
                self._client.close()
                self._client = None
            if self._cluster is not None:
                self._cluster.close()
                self._cluster = None

    def _stop_workers(self) -> None:
        """Stop the local cluster's workers within :data:`STOP_S` (killed mid-task), close it.

        Closing the cluster alone gives a busy worker 4 s to finish its task before it is
        killed; an abandoned task has nothing to finish.
        """
        with deferred(), suppress(Exception):  # closed below in any case
            nannies = list(self._cluster.workers.values())
            self._cluster.sync(_close_nannies, nannies, STOP_S)
        self.close()

    def client(self) -> Any:
        """Return the Dask client, starting the local cluster or connecting first if needed."""
        if self._client is not None:
            return self._client
        if not dask_installed():
            raise SchedulerError(
                f"{self.spec.describe()} needs Dask, which is not installed ({CLUSTER_INSTALL}); "
                "without it, --scheduler takes 'local', 'local:N' or 'inline'"
            )
        from distributed import Client, LocalCluster

        if self.spec.kind == "local":
            # the workers ignore Ctrl-C (this process shuts them down, see twin.core.interrupts):
            # started with SIGINT ignored, restarted ones by the preload; a Ctrl-C while the
            # cluster starts is raised once it has started, so that it is closed as a whole.
            # The thread that starts the stdlib's resource tracker unblocks SIGINT in itself
            # (bpo-33613), where it would be ignored: it is started from this thread first.
            resource_tracker.ensure_running()
            with deferred():
                self._cluster = LocalCluster(
                    n_workers=self.spec.workers or cpu_count(),
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=":0",  # a free port: two clusters at once do not clash
                    silence_logs=logging.CRITICAL,
                    preload=[WORKER_SETUP],
                )
                self._client = Client(self._cluster)
            return self._client
        if self.spec.kind != "remote":
            raise UsageError("an inline engine has no Dask client")
        problem = what_answers(self.spec.address, HANDSHAKE_TIMEOUT_S)
        if problem is not None:
            raise SchedulerError(
                f"no Dask scheduler at {self.spec.address}: {problem}; start one with `dask "
                "scheduler` and workers with `dask worker ADDRESS`"
            )
        try:
            client = Client(self.spec.address, timeout=f"{HANDSHAKE_TIMEOUT_S}s")
        except OSError as e:  # it greeted as Dask does, but did not go on as a scheduler
            raise SchedulerError(
                f"no Dask scheduler answered at {self.spec.address} within "
                f"{HANDSHAKE_TIMEOUT_S:g} s ({str(e) or type(e).__name__}); start one with `dask "
                "scheduler` and workers with `dask worker ADDRESS`"
            ) from None
        try:
            client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
            mine = _twin_version()
            theirs = client.run(_twin_version)
        except (TimeoutError, OSError) as e:
            client.close()
            raise SchedulerError(
                f"the Dask scheduler at {self.spec.address} has no worker (waited "
                f"{CONNECT_TIMEOUT_S:g} s: {e}); start one with `dask worker {self.spec.address}`"
            ) from None
        except Exception as e:  # a worker without the twin installed cannot run _twin_version
            client.close()
            raise SchedulerError(
                f"the workers of {self.spec.address} cannot run the twin ({type(e).__name__}: "
                f"{e}); install it on each worker machine (pip install twin=={_twin_version()})"
            ) from None
        other = {w: v for w, v in theirs.items() if v != mine}
        if other:
            client.close()
            raise SchedulerError(
                f"workers of {self.spec.address} run another twin version than this one "
                f"({mine}): {other}; results would not be those of this version"
            )
        self._client = client
        return client

    def map(
        self,
        fn: Callable[..., Any],
        args: Sequence[tuple],
        inputs: Sequence[Mapping[str, Any]],
        what: str,
        progress: ProgressFn | None = None,
    ) -> Outcome:
        """Run ``fn(*a)`` for each ``a`` in ``args``; results in input order.

        Parameters
        ----------
        fn : callable
            A module-level function (workers import it by name), pure in its arguments.
        args : sequence of tuple
            The arguments of each task.
        inputs : sequence of dict
            What to name each task by if it fails (same length as ``args``).
        what : str
            What the tasks are, plural (progress and messages), e.g. ``"subjects"``.
        progress : callable, optional
            Called with ``(what, done, total)`` as tasks finish (:mod:`twin.core.progress`).

        Returns
        -------
        Outcome
            Every result that came back, and the failures with their inputs.

        Notes
        -----
        A batch left by an exception (Ctrl-C) cancels its tasks; a local cluster is shut down
        too, as Dask does not stop a task that is running: so no worker writes on into a
        folder the caller then removes. The next batch starts another cluster.

        """
        if len(inputs) != len(args):
            raise ValueError(f"{len(args)} tasks but {len(inputs)} input descriptions")
        n = len(args)
        if progress:
            progress(what, 0, n)
        if self.spec.kind == "inline" or (self.spec.kind == "local" and n <= 1):
            return self._inline(fn, args, inputs, what, progress)
        if self.spec.kind == "local" and not dask_installed():
            return self._processes(fn, args, inputs, what, progress)
        return self._dask(fn, args, inputs, what, progress)

    @staticmethod
    def _inline(fn, args, inputs, what, progress) -> Outcome:
        out = Outcome(what, [None] * len(args))
        for i, a in enumerate(args):
            try:
                out.results[i] = fn(*a)
            except (Exception, SystemExit) as e:  # reported with its inputs; the others go on
                out.failures.append(_failure(i, inputs[i], e, e.__traceback__))
            if progress:
                progress(what, i + 1, len(args))
        return out

    def _processes(self, fn, args, inputs, what, progress) -> Outcome:
        """Run the tasks on a pool of the standard library's worker processes (no Dask).

        Spawned, not forked (MuJoCo's and BLAS's threads do not survive a fork), each set up as
        a Dask worker is (:func:`twin.core.tasks.worker_setup.process_setup`): SIGINT ignored
        (the workers start at the submits, inside :func:`~twin.core.interrupts.deferred`, so
        they inherit it ignored) and one BLAS thread (asked for here, before they start, so
        that they inherit it before they load NumPy). A worker that dies breaks the pool: the
        tasks not done are reported as failed.
        """
        from concurrent.futures import ProcessPoolExecutor, as_completed
        from concurrent.futures.process import BrokenProcessPool

        workers = min(self.spec.workers or cpu_count(), len(args))
        context = multiprocessing.get_context("spawn")
        out = Outcome(what, [None] * len(args))
        single_blas_thread()
        pool = ProcessPoolExecutor(workers, mp_context=context, initializer=process_setup)
        index: dict[Any, int] = {}
        try:
            with deferred():  # a Ctrl-C while the workers start is raised once they have
                for i, a in enumerate(args):
                    try:
                        index[pool.submit(fn, *a)] = i
                    except BrokenProcessPool as e:  # a worker died: none of the rest can run
                        out.failures += [_failure(k, inputs[k], e, None)
                                         for k in range(i, len(args))]  # fmt: skip
                        break
            for done, fut in enumerate(as_completed(index), 1):
                i = index[fut]
                try:
                    out.results[i] = fut.result()  # a worker's error, its traceback chained
                except (Exception, SystemExit) as e:
                    out.failures.append(_failure(i, inputs[i], e, e.__traceback__))
                if progress:
                    progress(what, done, len(args))
        except BaseException:  # abandoned (Ctrl-C): no worker writes on into removed folders
            with deferred():  # a second Ctrl-C does not cut the workers' stop short
                _terminate(pool)
            raise
        pool.shutdown(wait=True)
        out.failures.sort(key=lambda f: f.index)
        return out

    def _dask(self, fn, args, inputs, what, progress) -> Outcome:
        from distributed import as_completed

        client = self.client()
        futures = [client.submit(fn, *a, pure=False) for a in args]
        index = {f.key: i for i, f in enumerate(futures)}
        out = Outcome(what, [None] * len(args))
        try:
            for done, fut in enumerate(as_completed(futures), 1):
                i = index[fut.key]
                try:
                    out.results[i] = fut.result()  # raises the task's error, or a transfer's
                except (Exception, SystemExit) as e:
                    tb = fut.traceback() if fut.status == "error" else e.__traceback__
                    out.failures.append(_failure(i, inputs[i], e, tb))
                fut.release()
                if progress:
                    progress(what, done, len(args))
        except BaseException:  # the batch is abandoned (Ctrl-C): its tasks must not run on
            client.cancel(futures)
            if self._cluster is not None:  # a running task is not cancelled: its worker is
                self._stop_workers()  # stopped before the caller removes what it was writing
            raise
        out.failures.sort(key=lambda f: f.index)
        return out


def _terminate(pool: Any) -> None:
    """Stop a process pool's workers now (a running task is not cancelled otherwise)."""
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        proc.terminate()
    pool.shutdown(wait=True, cancel_futures=True)


async def _close_nannies(nannies: list[Any], timeout_s: float) -> None:
    """Close Dask nannies (their workers killed after ``timeout_s``), all at once."""
    await asyncio.gather(*(n.close(timeout=timeout_s) for n in nannies))


@contextmanager
def using(scheduler: Engine | str | None) -> Iterator[Engine]:
    """Yield an engine for a library function's ``scheduler=`` argument.

    Parameters
    ----------
    scheduler : Engine, str or None
        An engine (used and left open: the caller owns it), a ``--scheduler`` value (an
        engine made for the call and closed after it), or None: this process (``inline``),
        so that a library call starts no processes unless asked to.

    """
    if isinstance(scheduler, Engine):
        yield scheduler
        return
    with Engine(scheduler if scheduler is not None else "inline") as engine:
        yield engine
