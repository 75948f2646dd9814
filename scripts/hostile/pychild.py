"""The child interpreter of battery.py's Python cases.

Usage: python pychild.py BATCH.json FD START

Runs the cases of BATCH.json from index START, each in its own directory, and reports on
the file descriptor FD one JSON line per event: {"ev": "ready"}, then per case
{"ev": "start", "i"} and {"ev": "end", "i", "status", ...}, then {"ev": "done"}. Each case
starts with a marker on stderr (`@@hostile-case I`), so that what the case (or Rust under
it) wrote there can be told apart. The parent watches the time between start and end (a
hang) and whether the interpreter dies (an abort).
"""
import gc
import glob
import json
import os
import sys
import tempfile
import threading
import time
import traceback


def main() -> None:
    batch_file, fd, start = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    with open(batch_file) as f:
        batch = json.load(f)
    out = os.fdopen(fd, "w", buffering=1)

    def send(**ev):
        out.write(json.dumps(ev) + "\n")
        out.flush()

    import numpy as np  # noqa: F401
    import etlcal  # noqa: F401
    import prelude

    prelude.FX = batch["fx"]
    base = prelude.namespace()
    send(ev="ready")
    tmp = tempfile.gettempdir()
    pid = os.getpid()
    for i in range(start, len(batch["cases"])):
        c = batch["cases"][i]
        os.write(2, f"\n@@hostile-case {i}\n".encode())
        send(ev="start", i=i)
        os.chdir(c["dir"])
        before = set(glob.glob(os.path.join(tmp, f"etl-vlens-{pid}-*")))
        nthreads = threading.active_count()
        ns = dict(base)
        t0 = time.perf_counter()
        r = {}
        try:
            exec(compile(c["code"], c["name"], "exec"), ns)
            r["status"] = "ok"
            v = ns.get("RESULT", None)
            try:
                r["value"] = repr(v)[:300]
            except BaseException as e:  # noqa: BLE001
                r["value"] = f"<repr raised {type(e).__name__}>"
        except BaseException as e:  # noqa: BLE001 - the point is to see everything
            r = describe(e)
        dt = time.perf_counter() - t0
        ns.clear()
        del ns
        gc.collect()
        # Threads a case started are given a moment to end before the folders are looked at.
        t_end = time.monotonic() + 3
        while threading.active_count() > nthreads and time.monotonic() < t_end:
            time.sleep(0.01)
        gc.collect()
        left = sorted(set(glob.glob(os.path.join(tmp, f"etl-vlens-{pid}-*"))) - before)
        t_end = time.monotonic() + 1
        while left and time.monotonic() < t_end:
            time.sleep(0.05)
            gc.collect()
            left = sorted(set(glob.glob(os.path.join(tmp, f"etl-vlens-{pid}-*"))) - before)
        if left:
            r["vlens_left"] = left
        r["threads_left"] = threading.active_count() - nthreads
        send(ev="end", i=i, seconds=round(dt, 4), **r)
    send(ev="done")


def describe(e: BaseException) -> dict:
    t = type(e)
    try:
        msg = str(e)
    except BaseException as e2:  # noqa: BLE001
        msg = f"<str raised {type(e2).__name__}>"
    import etlcal

    return {
        "status": "raised",
        "type": t.__name__,
        "module": t.__module__,
        "mro": [k.__name__ for k in t.__mro__],
        "is_error": isinstance(e, etlcal.Error),
        "is_exception": isinstance(e, Exception),
        "msg": msg[:4000],
        "msg_len": len(msg),
        "where": "".join(traceback.format_exception(t, e, e.__traceback__)[-3:])[-800:],
    }


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    main()
