"""Many records on dask: a fleet's records streamed through the current dask scheduler.

tsfdi works one record at a time: the windowed engine filters a record once through every model, the monitor runs
over one stream. A fleet is many records. An xarray ``Dataset`` or ``DataArray`` backed by dask and chunked along
``record`` -- ``xarray.open_zarr(path)``, ``xarray.open_dataset(path, chunks={"record": 50})`` or
``make_hexacopter_dataset(..., chunks=50)`` -- is one more input kind of :func:`tsfdi.evaluate`,
:func:`tsfdi.fit_baselines` and :meth:`tsfdi.Monitor.screen`. Its chunks of records go to the current dask scheduler
(the threads or processes scheduler, or a ``dask.distributed`` Client: whichever ``dask.compute`` would use), each
chunk is read and processed where it runs, and the results come back chunk by chunk, in record order, with at most
a few chunks per worker in flight: the driver never holds the records, and the results are those of the serial
loop over the same records, in the same order.

:func:`map_records` is that loop, and the only place where tsfdi hands records to dask; :func:`compute` runs any
other dask computation (writing a simulated fleet to zarr or netCDF) on the same scheduler with a progress bar.

Examples
--------
>>> from distributed import Client, LocalCluster                              # doctest: +SKIP
>>> client = Client(LocalCluster(n_workers=4, threads_per_worker=1))           # doctest: +SKIP
>>> fleet = xarray.open_zarr("fleet.zarr")                                      # doctest: +SKIP
>>> ev = tsfdi.evaluate(fleet, baselines)   # the chunks run on the cluster     # doctest: +SKIP
"""

from __future__ import annotations

import os
import sys
from collections import deque
from collections.abc import Callable, Iterator
from typing import Any

from tsfdi._validation import boolean

__all__ = ["is_chunked", "record_chunks", "map_records", "compute", "dask_scheduler", "write_fleet",
           "worker_allocator"]

#: chunks of records in flight per worker thread: one running, one queued, so that no worker waits for the driver
AHEAD = 2


def _record_variables(data: Any) -> list:
    """The variables of an xarray object that run along ``record`` (data variables first)."""
    import xarray as xr

    if isinstance(data, xr.DataArray):
        return [data.variable] if "record" in data.dims else []
    if isinstance(data, xr.Dataset):
        return [v.variable for v in (*data.data_vars.values(), *data.coords.values()) if "record" in v.dims]
    return []


def is_chunked(data: Any) -> bool:
    """Whether ``data`` is an xarray ``Dataset`` / ``DataArray`` with a ``record`` dimension whose values are dask
    arrays (read or computed chunk by chunk), the input kind that :func:`map_records` streams."""
    return any(v.chunks is not None for v in _record_variables(data))


def record_chunks(data: Any) -> list[slice]:
    """The chunks of records of ``data``: one slice of record positions per dask chunk along ``record``, from the
    first dask-backed variable along it (data variables before coordinates); one slice of every record for data not
    backed by dask.

    Raises
    ------
    TypeError
        ``data`` is not an xarray object with a ``record`` dimension.
    """
    variables = _record_variables(data)
    if not variables:
        raise TypeError(f"data must be an xarray Dataset or DataArray with a 'record' dimension, got "
                        f"{type(data).__name__}")
    lazy = next((v for v in variables if v.chunks is not None), None)
    sizes = lazy.chunksizes["record"] if lazy is not None else (data.sizes["record"],)
    out, start = [], 0
    for size in sizes:
        out.append(slice(start, start + int(size)))
        start += int(size)
    return out


def _client() -> Any:
    """The ``dask.distributed`` Client that ``dask.compute`` would use now, else None."""
    from dask.base import get_scheduler

    get = get_scheduler()
    owner = getattr(get, "__self__", None)
    try:
        from distributed import Client
    except ImportError:
        return None
    return owner if isinstance(owner, Client) else None


def _workers(client: Any) -> int:
    """Worker threads of the current scheduler."""
    if client is not None:
        return max(1, sum(client.nthreads().values()))
    import dask
    from dask.base import get_scheduler

    get = get_scheduler()
    if get is not None and getattr(get, "__module__", "") == "dask.local":     # the synchronous scheduler
        return 1
    return max(1, int(dask.config.get("num_workers", None) or os.cpu_count() or 1))


#: glibc allocator thresholds set on a ``dask.distributed`` worker (:func:`worker_allocator`): blocks below 32 MiB
#: come from the heap and up to 64 MiB of freed memory stays there, instead of every block above 128 KiB being
#: mapped and returned to the kernel (which dask's default ``MALLOC_TRIM_THRESHOLD_=65536`` causes)
MALLOC_MMAP_THRESHOLD = 32 * 2**20
MALLOC_TRIM_THRESHOLD = 64 * 2**20
_allocator_set = False


def worker_allocator() -> bool:
    """On a ``dask.distributed`` worker process with glibc, keep freed memory in the process: the allocator's mmap
    threshold set to :data:`MALLOC_MMAP_THRESHOLD` and its trim threshold to :data:`MALLOC_TRIM_THRESHOLD`
    (``mallopt``), once per process. Called by :func:`map_records` on the worker before its first chunk.

    dask's nanny starts workers with ``MALLOC_TRIM_THRESHOLD_=65536`` (``distributed.nanny.pre-spawn-environ``), so
    that memory goes back to the kernel; setting it also turns off glibc's adaptive mmap threshold, so that every
    temporary array above 128 KiB is mapped and unmapped: evaluating the shipped data on one worker then costs about
    520,000 page faults and 0.6-0.7 s of system time (1,000 faults and 0.05 s after). A worker whose environment
    sets ``MALLOC_MMAP_THRESHOLD_`` is left as it is (the user chose), as is any process that is not a dask worker
    (the driver, dask's threads and processes schedulers: glibc's adaptive thresholds apply there; a
    ``LocalCluster(processes=False)`` runs its workers in the driver's process, which they then set).

    Returns
    -------
    bool
        Whether the thresholds are set in this process (now or by an earlier call).
    """
    global _allocator_set
    if _allocator_set:
        return True
    if "MALLOC_MMAP_THRESHOLD_" in os.environ or not sys.platform.startswith("linux"):
        return False
    try:
        from distributed import get_worker

        get_worker()
    except (ImportError, ValueError):
        return False
    import ctypes
    import platform

    if platform.libc_ver()[0] != "glibc":
        return False
    libc = ctypes.CDLL("libc.so.6")
    # mallopt parameters of glibc's malloc.h: M_TRIM_THRESHOLD -1, M_MMAP_THRESHOLD -3; 1 = accepted
    _allocator_set = bool(libc.mallopt(-3, MALLOC_MMAP_THRESHOLD)) & bool(libc.mallopt(-1, MALLOC_TRIM_THRESHOLD))
    return _allocator_set


def _call(func: Callable, chunk: Any, where: slice, args: tuple) -> Any:
    worker_allocator()
    return func(chunk, where, *args)


def _read_call(func: Callable, data: Any, select: slice, where: slice, args: tuple) -> Any:
    """:func:`_call` on the chunk ``where``, the records ``select`` of ``data`` (still backed by dask: the whole
    fleet, sent to the workers once, or the chunk alone), read here, in this task, by dask's synchronous scheduler."""
    return _call(func, data.isel(record=select).compute(scheduler="synchronous"), where, args)


#: bytes of records in memory per chunk up to which :func:`map_records` sends the fleet to every worker once (a
#: fleet read from a store: its graph, the reads, and its labels); above, the records are held in memory (a fleet
#: chunked with ``.chunk()``), and each chunk goes in its own task instead of the whole fleet to every worker
HELD_PER_CHUNK = 2**16


def _held_bytes(data: Any) -> int:
    """Bytes of the arrays that ``data``'s dask graph holds and of its variables along ``record`` in memory."""
    import numpy as np

    graph = data.__dask_graph__()
    held = 0 if graph is None else sum(v.nbytes for v in graph.values() if isinstance(v, np.ndarray))
    return int(held) + sum(v.nbytes for v in _record_variables(data) if v.chunks is None)


def map_records(func: Callable, data: Any, *args: Any, progress: bool = False, desc: str = "tsfdi") -> Iterator:
    """``func(chunk, where, *args)`` for every chunk of records of ``data``, run on the current dask scheduler and
    yielded in record order.

    Parameters
    ----------
    func : callable
        Called once per chunk with ``chunk``, the chunk's records read into memory (an xarray object of the kind of
        ``data``, its values numpy arrays), ``where``, the slice of their positions in ``data``, and ``args``. It runs
        on a worker: with processes or a distributed cluster it must be picklable (a module-level function), and
        what it returns travels back to the driver, so it should return what the records reduce to, not the records.
    data : xarray.Dataset or xarray.DataArray
        Records along a ``record`` dimension, backed by dask (:func:`is_chunked`); each dask chunk along ``record``
        is one call (:func:`record_chunks`). Rechunk with ``data.chunk(record=n)`` for another granularity.
    *args
        Passed to every call. With a distributed Client they are sent to every worker once
        (``Client.scatter(broadcast=True)``), not once per chunk, and kept there for the next calls with the same
        arguments (the same dask token; the last :data:`SCATTERED` sets of arguments of each of the last
        :data:`SCATTERED` Clients).
    progress : bool
        Show a tqdm progress bar over the records.
    desc : str
        Label of the progress bar.

    Yields
    ------
    object
        ``func``'s result of each chunk, in record order.

    Notes
    -----
    With a ``dask.distributed`` Client (the one ``dask.compute`` would use) ``data``, still lazy (its graph, not its
    records), is sent to every worker once per call (``Client.scatter(broadcast=True)``), and every chunk is one task
    (``Client.submit``) that names its records: the worker selects them and reads them (their part of ``data``'s
    graph, computed there by dask's synchronous scheduler: one task per chunk for the cluster's scheduler, not one
    per variable and step of the read; the driver and the scheduler never handle the reads). Records held in memory
    (``data`` chunked with ``.chunk()``: more than :data:`HELD_PER_CHUNK` bytes per chunk in its graph or its
    variables) go instead each chunk in its own task, culled here, not all to every worker. At most ``AHEAD``
    chunks per worker thread are in flight; the driver waits for the
    oldest, so the results come in order and a slow chunk holds back at most that many. With the threads, processes
    or synchronous scheduler the chunks are computed ``AHEAD`` per worker at a time by ``dask.compute``. Either way
    the driver holds at most that many results at once, whatever the number of records. An exception raised by
    ``func`` on a worker is raised here, with its type. On a ``dask.distributed`` worker the allocator is set once
    per process by :func:`worker_allocator` before the first chunk.
    """
    import dask

    progress = boolean(progress, "progress")
    if not callable(func):
        raise TypeError(f"func must be callable, got {type(func).__name__}")
    chunks = record_chunks(data)
    client = _client()
    ahead = AHEAD * _workers(client)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=int(data.sizes["record"]), desc=desc, unit="record")
    try:
        if client is None:
            for first in range(0, len(chunks), ahead):
                batch = chunks[first:first + ahead]
                results = dask.compute(*[dask.delayed(_call)(func, data.isel(record=s), s, args) for s in batch])
                for s, result in zip(batch, results):
                    if bar is not None:
                        bar.update(s.stop - s.start)
                    yield result
            return
        shared = _scatter(client, args)
        # a fleet read from a store: the fleet, still lazy (its graph: ~15 kB per chunk), goes to every worker once,
        # and each task names its chunk: one task per chunk, which selects and reads its records itself. Neither
        # the driver nor the scheduler handles the reads: an optimized graph per chunk in each task cost the driver
        # ~7 ms and the scheduler ~3 ms of CPU time per chunk (culling, pickling, unpickling zarr's arrays), which
        # the workers lack when they have all the cores. A fleet whose graph holds its records (in memory): each
        # task carries its chunk's part, culled here
        once = _held_bytes(data) <= HELD_PER_CHUNK * len(chunks)
        fleet = client.scatter([data], broadcast=True, hash=False)[0] if once else None
        queue: deque = deque()
        try:
            for s in chunks:
                task = (fleet, s) if once else (dask.optimize(data.isel(record=s))[0], slice(None))
                queue.append((s, client.submit(_read_call, func, *task, s, shared, pure=False)))
                if len(queue) >= ahead:
                    yield _next(queue, bar)
            while queue:
                yield _next(queue, bar)
        finally:
            if queue:
                client.cancel([f for _, f in queue])
    finally:
        if bar is not None:
            bar.close()


#: sets of ``map_records`` arguments kept on the cluster of each of the last ``SCATTERED`` Clients used, so that a
#: later call with the same arguments (the same baselines) refers to them instead of sending them again
SCATTERED = 2
#: Client id -> (the Client, {token of the arguments: their Future}), oldest first
_scattered: dict = {}


def _scatter(client: Any, args: tuple) -> Any:
    """A Future of ``args`` on ``client``'s cluster: sent to every worker (``Client.scatter(broadcast=True)``) the
    first time, the same Future when arguments with the same dask token were sent before and are still there."""
    from dask.base import tokenize

    for key in [k for k, (c, _) in _scattered.items() if c.status in ("closing", "closed")]:
        del _scattered[key]
    _, cache = _scattered.pop(client.id, (client, {}))
    _scattered[client.id] = (client, cache)
    while len(_scattered) > SCATTERED:
        del _scattered[next(iter(_scattered))]
    token = tokenize(args)
    future = cache.pop(token, None)
    if future is None or future.status != "finished":
        future = client.scatter([args], broadcast=True, hash=False)[0]
    cache[token] = future
    while len(cache) > SCATTERED:
        del cache[next(iter(cache))]
    return future


def _next(queue: deque, bar: Any) -> Any:
    where, future = queue.popleft()
    result = future.result()
    if bar is not None:
        bar.update(where.stop - where.start)
    return result


def compute(obj: Any, *, progress: bool = False) -> Any:
    """Compute a dask object (an array, a Dataset, the ``Delayed`` of ``Dataset.to_zarr(..., compute=False)``), or a
    list of them in one graph, on the current dask scheduler, with dask's progress bar.

    Parameters
    ----------
    obj : dask collection or list of them
    progress : bool
        Show ``distributed.progress`` with a Client, else ``dask.diagnostics.ProgressBar`` (on stderr).

    Returns
    -------
    object
        The computed value.
    """
    import dask

    progress = boolean(progress, "progress")
    client = _client()
    if client is not None:
        future = client.compute(obj)
        if progress:
            from distributed import progress as show

            show(future)
        return client.gather(future)
    if not progress:
        return dask.compute(obj)[0]
    from dask.diagnostics import ProgressBar

    with ProgressBar(out=sys.stderr):
        return dask.compute(obj)[0]


def dask_scheduler(value: str) -> Any:
    """A context in which ``dask.compute`` runs on the scheduler ``value`` names: ``"threads"``, ``"processes"``,
    ``"synchronous"``, or the address of a running ``dask.distributed`` scheduler (``"tcp://10.0.0.1:8786"``), to
    which a ``Client`` is connected (closed when the context ends).

    Raises
    ------
    ValueError
        Another name, or an address that cannot be reached (within 10 s).
    """
    import dask

    if isinstance(value, str) and "://" in value:
        from distributed import Client

        try:
            return Client(value, timeout="10s")
        except (OSError, ValueError) as exc:
            raise ValueError(f"scheduler {value}: cannot connect to the dask scheduler ({exc})") from None
    if value in ("threads", "processes", "synchronous"):
        return dask.config.set(scheduler=value)
    raise ValueError(f"scheduler must be threads, processes, synchronous or the address of a dask.distributed "
                     f"scheduler such as tcp://10.0.0.1:8786, got {value!r}")


def write_fleet(ds: Any, path: str | os.PathLike, *, encoding: dict | None = None, scheduler: str = "threads",
                progress: bool = False) -> None:
    """Write a ``Dataset`` backed by dask and chunked along ``record`` chunk by chunk on a dask scheduler: a zarr
    store (format 2) for a name ending in ``.zarr``, else a netCDF file; memory holds a few chunks at a time.

    Parameters
    ----------
    ds : xarray.Dataset
    path : str or path-like
    encoding : dict, optional
        Per variable, as ``Dataset.to_netcdf``; for zarr only ``dtype``, ``scale_factor`` and ``_FillValue`` are
        kept (zarr's own compressor). A zarr store holds each variable along ``record`` alone (a label such as
        ``seed`` or ``lost_control``: a few bytes per record) in one chunk, so that a reader gets it in one read,
        not one per chunk of records (:func:`~tsfdi.datasets.hexacopter_signals` of a store of 2,000 records in
        chunks of 50: 0.18 s with its eight labels in 320 chunks, 0.01 s with each in one); the labels backed by dask (computed by the
        simulation, e.g. ``lost_control``) are computed with the data and written after it. ``Dataset.chunks`` of
        such a store raises (its labels are chunked apart from the data): ask a data variable,
        ``store["roll"].chunks``.
    scheduler : str
        As :func:`dask_scheduler`. ``"processes"`` cannot write a netCDF file (dask's local processes share no lock on
        it): write a zarr store, or use threads or a ``dask.distributed`` scheduler.
    progress : bool
        Show a progress bar.
    """
    import xarray as xr

    zarr = os.fspath(path).lower().endswith(".zarr")
    enc = dict(encoding or {})
    labels = [c for c, v in ds.variables.items() if v.dims == ("record",) and c != "record"] if zarr else []
    lazy = [c for c in labels if ds[c].chunks is not None]
    if zarr:
        enc = {v: {k: e[k] for k in ("dtype", "scale_factor", "_FillValue") if k in e} for v, e in enc.items()}
        for c in labels:
            enc[c] = {**enc.get(c, {}), "chunks": (ds.sizes["record"],)}
    elif scheduler == "processes":
        raise ValueError("scheduler processes cannot write a netCDF file (the processes of dask's local scheduler "
                         "share no lock on it): write a .zarr store, or use threads or a dask.distributed scheduler")
    with dask_scheduler(scheduler):
        if zarr:
            # a dask label would be written chunk by chunk into one zarr chunk (writes that race): computed in the
            # same graph as the data (one simulation per chunk feeds both), then written whole
            store = ds.drop_vars(lazy).to_zarr(path, mode="w", encoding={k: e for k, e in enc.items() if k not in lazy},
                                               compute=False, zarr_format=2)
            _, *values = compute([store, *(ds[c].data for c in lazy)], progress=progress)
            if lazy:
                done = {c: ds[c].variable.copy(data=v) for c, v in zip(lazy, values)}
                xr.Dataset({c: v for c, v in done.items() if c in ds.data_vars},
                           coords={c: v for c, v in done.items() if c in ds.coords}).to_zarr(
                    path, mode="a", encoding={c: enc[c] for c in lazy}, zarr_format=2)
        else:
            compute(ds.to_netcdf(path, engine="h5netcdf", encoding=enc, compute=False), progress=progress)
