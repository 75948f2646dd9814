#!/usr/bin/env python3
"""Hostile-user battery over the etlcal command line and the etlcal Python package.

Every case runs in a fresh directory of its own and is judged on four failure classes:

- data loss: a file, link or folder that existed before the case (inputs, sentinels,
  earlier outputs) changed or vanished, when the command failed, was refused or killed
  (on success, only the outputs the case names may change);
- uncatchable: CLI: a panic (exit 101, "panicked at"), death by a signal, a Rust backtrace;
  Python: anything but etlcal.Error (and subclasses) or a plain TypeError/ValueError
  (PanicException, BaseException that is not Exception, RuntimeError, ...; OverflowError from
  converting an int too large, as Python's float() raises it, is allowed),
  or the child interpreter dying (abort: exit -6/134, any signal);
- hang: the case's timeout passed;
- leak: a temporary left in the case's directory (a new hidden entry other than
  `.etlcal-set`: `.NAME.tmpPID`, `.NAME.etlcal-pending`, ...), or a /tmp/etl-vlens-PID-N
  folder of a process that has ended.

Soft findings, reported apart and not counted in the four classes: `message` (a refusal
whose stderr or exception text is not one short line, exits other than 1/2, or prints a
number with more than 17 significant digits), `accepted` (a value the documentation says
is refused was accepted) and `baseline` (a valid command of the battery failed, so its
mutations test less than they should).

Usage: python battery.py [--fast] [--binary PATH] [--json OUT] [--seed N] [--jobs N]
                         [--timeout S] [--filter TEXT] [--list] [--keep]
Run it with the Python that has etlcal and numpy installed (the child interpreters
are that Python). Exit status 1 when any case fails one of the four classes.
"""
import argparse
import concurrent.futures
import glob
import hashlib
import json
import os
import random
import re
import resource
import select
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time
import zlib
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)

CLASSES = ("data-loss", "uncatchable", "hang", "leak")
SOFT = ("message", "accepted", "baseline")
MAX_KEEP = 256 * 1024  # bytes of each stream kept for judging


# ---------------------------------------------------------------------------------------
# Cases


@dataclass
class Case:
    name: str
    family: str
    kind: str  # "cli", "py", "custom"
    setup: Optional[Callable[[str], None]] = None  # fills the case directory
    argv: List[str] = field(default_factory=list)  # cli: arguments after the binary
    env: Dict[str, Optional[str]] = field(default_factory=dict)  # None removes a variable
    expect: str = "any"  # "ok", "refuse", "any"
    outputs: List[str] = field(default_factory=list)  # paths that may change on success
    timeout: Optional[float] = None
    fast: bool = False
    code: str = ""  # py: the snippet
    isolate: bool = False  # py: an interpreter of its own
    allowed: List[str] = field(default_factory=list)  # py: extra exception names allowed
    runner: Optional[Callable[["Case", "Ctx", str], "Result"]] = None  # custom
    note: str = ""
    echo: List[str] = field(default_factory=list)  # numbers the user typed (not flagged)
    protect: List[str] = field(default_factory=list)  # must stay as they are even on success
    multiline: bool = False  # a refusal may name many things, one line each
    no_message: bool = False  # the message echoes what the user gave (a 5000-character path)


@dataclass
class Result:
    name: str
    family: str
    kind: str
    failures: List[Dict[str, str]] = field(default_factory=list)  # {"class", "what"}
    soft: List[Dict[str, str]] = field(default_factory=list)
    detail: Dict[str, Any] = field(default_factory=dict)
    seconds: float = 0.0

    def fail(self, cls: str, what: str) -> None:
        self.failures.append({"class": cls, "what": what})

    def warn(self, cls: str, what: str) -> None:
        self.soft.append({"class": cls, "what": what})


class Ctx:
    """What every case needs: the binary, the fixtures, the options."""

    def __init__(self, args: argparse.Namespace, root: str):
        self.args = args
        self.root = root
        self.binary = os.path.join(root, "bin", "etlcal")
        self.python = args.python
        self.fx = os.path.join(root, "fx")
        self.cases_dir = os.path.join(root, "cases")
        self.logs = os.path.join(root, "logs")
        self.timeout = args.timeout
        self.mem = int(args.mem_limit_gb * (1 << 30))
        self.rng = random.Random(args.seed)
        self.lock = threading.Lock()
        self.children: List[int] = []
        self.counter = 0
        self.info: Dict[str, Any] = {}

    def new_dir(self, name: str) -> str:
        with self.lock:
            self.counter += 1
            n = self.counter
        slug = re.sub(r"[^A-Za-z0-9._=-]+", "_", name)[-80:]
        d = os.path.join(self.cases_dir, f"{n:05d}-{slug}")
        os.makedirs(d)
        return d

    def fxp(self, name: str) -> str:
        return os.path.join(self.fx, name)


def limits(mem: int) -> Callable[[], None]:
    def f() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (mem, mem))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))

    return f


# ---------------------------------------------------------------------------------------
# Snapshots: what a directory holds, byte for byte


def file_digest(path: str, size: int) -> str:
    if size > 64 << 20:  # a sparse or huge file: its size and first MiB
        with open(path, "rb") as f:
            return f"big:{size}:{hashlib.sha256(f.read(1 << 20)).hexdigest()}"
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def snapshot(d: str) -> Dict[str, tuple]:
    snap: Dict[str, tuple] = {}
    for root, dirs, files in os.walk(d):
        for name in dirs + files:
            p = os.path.join(root, name)
            rel = os.path.relpath(p, d)
            try:
                st = os.lstat(p)
            except OSError:
                continue
            m = st.st_mode
            if stat.S_ISLNK(m):
                snap[rel] = ("link", os.readlink(p))
            elif stat.S_ISDIR(m):
                snap[rel] = ("dir",)
            elif stat.S_ISREG(m):
                try:
                    snap[rel] = ("file", file_digest(p, st.st_size))
                except OSError as e:
                    snap[rel] = ("file", f"unreadable:{e.errno}")
            elif stat.S_ISFIFO(m):
                snap[rel] = ("fifo",)
            elif stat.S_ISCHR(m):
                snap[rel] = ("chr", st.st_rdev)
            else:
                snap[rel] = ("other",)
    return snap


def covered(rel: str, allowed: List[str]) -> bool:
    for a in allowed:
        a = os.path.normpath(a)
        if rel == a or rel.startswith(a + os.sep):
            return True
    return False


def check_tree(res: Result, pre: Dict[str, tuple], post: Dict[str, tuple], allowed: List[str],
               succeeded: bool, leaks: bool = True, protect: Optional[List[str]] = None) -> None:
    """Data loss and leftover temporaries, comparing a case directory before and after."""
    ok = allowed if succeeded else []
    lost = []
    for rel, v in sorted(pre.items()):
        if covered(rel, ok) and not covered(rel, protect or []):
            continue
        if rel not in post:
            lost.append(f"{rel} removed")
        elif post[rel] != v:
            lost.append(f"{rel} changed ({v[0]} -> {post[rel][0]})")
    if lost:
        # A removed directory also removes everything below it: name the top ones.
        res.fail("data-loss", "; ".join(lost[:6]) + (f"; ... {len(lost)} entries" if len(lost) > 6 else ""))
    if leaks:
        left = [rel for rel in sorted(set(post) - set(pre)) if is_temporary(rel)]
        if left:
            res.fail("leak", "left behind: " + ", ".join(left[:6]))


def is_temporary(rel: str) -> bool:
    b = os.path.basename(rel)
    if b == ".etlcal-set":
        return False
    return b.startswith(".") or ".tmp" in b or "etlcal-pending" in b


def vlens_dirs(pid: int, tmpdirs: List[str]) -> List[str]:
    out = []
    for t in tmpdirs:
        out += glob.glob(os.path.join(t, f"etl-vlens-{pid}-*"))
    return out


def pid_alive(pid: int) -> bool:
    return os.path.exists(f"/proc/{pid}")


# ---------------------------------------------------------------------------------------
# Messages

NUMBER = re.compile(r"(?<![\w.])[-+]?(\d+)(?:\.(\d+))?(?:[eE][-+]?\d+)?(?![\w])")


def sig_digits(intpart: str, frac: Optional[str]) -> int:
    i = intpart.lstrip("0")
    if i:
        return len(i) + len(frac or "")
    return len((frac or "").lstrip("0"))


def long_numbers(text: str, echo: List[str]) -> List[str]:
    found = []
    for m in NUMBER.finditer(text):
        if sig_digits(m.group(1), m.group(2)) > 17:
            tok = m.group(0)
            if any(tok.lstrip("+-") in e for e in echo):
                continue
            found.append(tok if len(tok) < 40 else tok[:20] + f"...({len(tok)} chars)")
    return found


def judge_message(res: Result, text: str, echo: List[str], cli: bool, rc: Optional[int] = None,
                  multiline: bool = False) -> None:
    lines = [ln for ln in text.splitlines() if ln.strip()]
    body = [ln for ln in lines if not ln.startswith("etlcal: warning:")]
    why = []
    if cli and rc not in (1, 2):
        why.append(f"exit status {rc}")
    if cli and not any(ln.startswith("etlcal: error:") for ln in lines):
        why.append("no 'etlcal: error:' line")
    if len(body) > 3 and not multiline:
        why.append(f"{len(body)} lines")
    if any(len(ln) > 1000 for ln in lines):
        why.append(f"a line of {max(len(ln) for ln in lines)} chars")
    nums = long_numbers(text, echo)
    if nums:
        why.append("numbers with more than 17 significant digits: " + ", ".join(nums[:3]))
    if why:
        first = body[0] if body else (lines[0] if lines else "")
        res.warn("message", "; ".join(why) + f" | {first[:300]}")


# ---------------------------------------------------------------------------------------
# Running a process with bounded output


class Capped:
    def __init__(self, stream):
        self.buf = bytearray()
        self.total = 0
        self.t = threading.Thread(target=self._run, args=(stream,), daemon=True)
        self.t.start()

    def _run(self, stream) -> None:
        while True:
            chunk = stream.read(65536)
            if not chunk:
                break
            self.total += len(chunk)
            if len(self.buf) < MAX_KEEP:
                self.buf += chunk[: MAX_KEEP - len(self.buf)]
        stream.close()

    def text(self) -> str:
        self.t.join(5)
        return self.buf.decode("utf-8", "replace")


@dataclass
class Proc:
    rc: Optional[int]
    stdout: str
    stderr: str
    timed_out: bool
    seconds: float
    pid: int
    stdout_total: int = 0


def run_proc(ctx: Ctx, argv: List[str], cwd: str, env_over: Dict[str, Optional[str]],
             timeout: float, stdin: Any = subprocess.DEVNULL) -> Proc:
    env = dict(os.environ)
    env.pop("RUST_BACKTRACE", None)
    env.pop("RUST_LIB_BACKTRACE", None)
    for k, v in env_over.items():
        if v is None:
            env.pop(k, None)
        else:
            env[k] = v
    t0 = time.monotonic()
    p = subprocess.Popen(argv, cwd=cwd, env=env, stdin=stdin, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, start_new_session=True,
                         preexec_fn=limits(ctx.mem))
    with ctx.lock:
        ctx.children.append(p.pid)
    out, err = Capped(p.stdout), Capped(p.stderr)
    timed_out = False
    try:
        p.wait(timeout)
    except subprocess.TimeoutExpired:
        timed_out = True
        kill_group(p)
    return Proc(p.returncode, out.text(), err.text(), timed_out, time.monotonic() - t0, p.pid, out.total)


def kill_group(p: subprocess.Popen) -> None:
    try:
        os.killpg(p.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    try:
        p.wait(10)
    except subprocess.TimeoutExpired:
        pass


BACKTRACE = re.compile(r"stack backtrace:|^\s+\d+: \S+::|^\s+at \S+\.rs:\d+", re.M)


def judge_proc(res: Result, pr: Proc, echo: List[str], expect: str, env: Dict[str, Optional[str]],
               multiline: bool = False) -> None:
    res.detail.update(rc=pr.rc, seconds=round(pr.seconds, 3), stderr=pr.stderr[-1500:],
                      stdout_head=pr.stdout[:300])
    if pr.timed_out:
        res.fail("hang", f"no exit after {pr.seconds:.0f} s (killed)")
        return
    if pr.rc is not None and pr.rc < 0:
        sig = signal.Signals(-pr.rc).name if -pr.rc in signal.Signals._value2member_map_ else str(-pr.rc)
        tail = pr.stderr.strip().splitlines()[-1:] or [""]
        res.fail("uncatchable", f"killed by {sig} | {tail[0][:300]}")
        return
    if pr.rc == 101 or "panicked at" in pr.stderr:
        m = re.search(r"panicked at [^\n]*\n?[^\n]*", pr.stderr)
        res.fail("uncatchable", f"panic (exit {pr.rc}) | {(m.group(0) if m else pr.stderr[:300]).strip()[:400]}")
        return
    if BACKTRACE.search(pr.stderr):
        if env.get("RUST_BACKTRACE"):
            res.warn("message", "a backtrace on stderr with RUST_BACKTRACE set")
        else:
            res.fail("uncatchable", "a Rust backtrace on stderr")
    if pr.rc != 0:
        judge_message(res, pr.stderr, echo, cli=True, rc=pr.rc, multiline=multiline)
        if expect == "ok":
            res.warn("baseline", f"exit {pr.rc}: {first_error(pr.stderr)}")
    elif expect == "refuse":
        res.warn("accepted", f"exit 0: {(pr.stdout.strip().splitlines() or pr.stderr.strip().splitlines() or [''])[0][:200]}")


def first_error(text: str) -> str:
    for ln in text.splitlines():
        if ln.startswith("etlcal: error:"):
            return ln[:300]
    return (text.strip().splitlines() or [""])[0][:300]


# ---------------------------------------------------------------------------------------
# CLI cases


def sentinel(d: str) -> None:
    with open(os.path.join(d, "sentinel.txt"), "wb") as f:
        f.write(b"sentinel " + os.urandom(24).hex().encode() + b"\n")


def run_cli_case(case: Case, ctx: Ctx) -> Result:
    res = Result(case.name, case.family, case.kind)
    d = ctx.new_dir(case.name)
    sentinel(d)
    if case.setup:
        case.setup(d)
    pre = snapshot(d)
    vl_before = set(glob.glob("/tmp/etl-vlens-*"))
    argv = [a.replace("{CASE}", d) if isinstance(a, str) else a for a in case.argv]
    pr = run_proc(ctx, [ctx.binary] + argv, d, case.env, case.timeout or ctx.timeout)
    res.seconds = pr.seconds
    echo = [a if isinstance(a, str) else os.fsdecode(a) for a in case.argv]
    judge_proc(res, pr, echo + [v or "" for v in case.env.values()] + case.echo, case.expect, case.env,
               multiline=case.multiline)
    post = snapshot(d)
    check_tree(res, pre, post, case.outputs, succeeded=(pr.rc == 0), leaks=not pr.timed_out, protect=case.protect)
    tmpdirs = ["/tmp"] + [v for k, v in case.env.items() if k == "TMPDIR" and v]
    if not pr.timed_out:
        left = [p for p in vlens_dirs(pr.pid, tmpdirs) if p not in vl_before]
        if left:
            res.fail("leak", f"virtual-lens folder of the ended process: {left[0]}")
    res.detail["dir"] = d
    return res


# ---------------------------------------------------------------------------------------
# Python cases: batches in child interpreters


def py_allowed(r: Dict[str, Any], allowed: List[str]) -> Optional[str]:
    """None when the exception is within the contract, else why not."""
    mro = r.get("mro", [])
    name = r.get("type", "")
    if r.get("is_error"):
        return None
    if name in allowed or any(a in mro for a in allowed):
        return None
    if "PanicException" in mro or r.get("module") == "pyo3_runtime":
        return f"PanicException: {r.get('msg', '')[:300]}"
    if not r.get("is_exception"):
        return f"{name} (a BaseException that is not an Exception): {r.get('msg', '')[:200]}"
    # OverflowError: Python's own conversion of an int too large for a float or a C integer
    # (float(10**400) raises it too), an Exception like TypeError and ValueError.
    if "TypeError" in mro or "ValueError" in mro or "OverflowError" in mro:
        return None
    return f"{r.get('module')}.{name}: {r.get('msg', '')[:300]}"


def run_py_batch(cases: List[Case], ctx: Ctx) -> List[Result]:
    results: Dict[int, Result] = {}
    dirs, pres = [], []
    for c in cases:
        d = ctx.new_dir(c.name)
        sentinel(d)
        if c.setup:
            c.setup(d)
        dirs.append(d)
        pres.append(snapshot(d))
    payload = {"fx": ctx.fx, "cases": [{"name": c.name, "dir": d, "code": c.code} for c, d in zip(cases, dirs)]}
    fd, bfile = tempfile.mkstemp(prefix="batch-", suffix=".json", dir=ctx.logs)
    with os.fdopen(fd, "w") as f:
        json.dump(payload, f)
    raw: Dict[int, Dict[str, Any]] = {}
    pids: Dict[int, int] = {}
    stderr_parts: Dict[int, str] = {}
    start = 0
    while start < len(cases):
        rfd, wfd = os.pipe()
        errlog = bfile + f".{start}.err"
        with open(errlog, "wb") as ef:
            env = dict(os.environ)
            env.pop("RUST_BACKTRACE", None)
            env["PYTHONFAULTHANDLER"] = "1"
            env["PYTHONDONTWRITEBYTECODE"] = "1"
            p = subprocess.Popen([ctx.python, os.path.join(HERE, "pychild.py"), bfile, str(wfd), str(start)],
                                 stdin=subprocess.DEVNULL, stdout=ef, stderr=ef, pass_fds=(wfd,),
                                 start_new_session=True, preexec_fn=limits(ctx.mem), env=env)
        os.close(wfd)
        with ctx.lock:
            ctx.children.append(p.pid)
        current = None
        got_done = False
        deadline = time.monotonic() + 60  # the import
        buf = b""
        ended = False
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            r, _, _ = select.select([rfd], [], [], min(left, 1.0))
            if not r:
                continue
            chunk = os.read(rfd, 65536)
            if not chunk:
                ended = True
                break
            buf += chunk
            while b"\n" in buf:
                line, buf = buf.split(b"\n", 1)
                ev = json.loads(line)
                if ev["ev"] == "start":
                    current = ev["i"]
                    pids[current] = p.pid
                    deadline = time.monotonic() + (cases[current].timeout or ctx.timeout)
                elif ev["ev"] == "end":
                    raw[ev["i"]] = ev
                    current = None
                    deadline = time.monotonic() + 30
                elif ev["ev"] == "ready":
                    deadline = time.monotonic() + 30
                elif ev["ev"] == "done":
                    got_done = True
                    deadline = time.monotonic() + 30
        os.close(rfd)
        ran_here = [i for i in raw if i >= start]
        if not ended:  # a hang: the case in progress (or the start-up)
            kill_group(p)
            i = current if current is not None else (max(ran_here) + 1 if ran_here else start)
            i = min(i, len(cases) - 1)
            raw.setdefault(i, {"ev": "hang", "i": i, "seconds": cases[i].timeout or ctx.timeout})
        else:
            try:
                p.wait(30)
            except subprocess.TimeoutExpired:
                kill_group(p)
                i = max(ran_here) if ran_here else start
                raw[i] = dict(raw.get(i, {}), ev="exit-hang")
        rc = p.returncode
        with open(errlog, "rb") as ef:
            err = ef.read().decode("utf-8", "replace")
        for m in re.finditer(r"@@hostile-case (\d+)\n(.*?)(?=\n@@hostile-case \d+\n|\Z)", err, re.S):
            stderr_parts[int(m.group(1))] = stderr_parts.get(int(m.group(1)), "") + m.group(2)
        if ended and not got_done:
            if current is not None and current not in raw:  # died during the case
                raw[current] = {"ev": "died", "i": current, "rc": rc}
            else:  # died between cases: the next one, or at start-up
                i = min(max(ran_here) + 1 if ran_here else start, len(cases) - 1)
                if i not in raw:
                    raw[i] = {"ev": "died", "i": i, "rc": rc, "between": True, "log": err[-800:]}
        elif ended and rc not in (0, None) and ran_here:
            last = max(ran_here)
            raw[last] = dict(raw[last], exit_rc=rc)
        done = [i for i in raw if i >= start]
        start = (max(done) + 1) if done else start + 1
    for i, c in enumerate(cases):
        res = Result(c.name, c.family, c.kind)
        r = raw.get(i, {"ev": "missing"})
        res.detail.update(r)
        res.detail["dir"] = dirs[i]
        res.seconds = r.get("seconds", 0.0)
        err = stderr_parts.get(i, "")
        if err.strip():
            res.detail["stderr"] = err[-1500:]
        ev = r.get("ev")
        succeeded = False
        if ev in ("hang", "exit-hang"):
            res.fail("hang", f"no result after {c.timeout or ctx.timeout:.0f} s" if ev == "hang"
                     else "the interpreter did not exit after the case")
        elif ev == "died":
            rcv = r.get("rc")
            what = f"signal {signal.Signals(-rcv).name}" if isinstance(rcv, int) and rcv < 0 else f"exit {rcv}"
            tail = [ln for ln in err.strip().splitlines() if ln.strip()][-2:]
            res.fail("uncatchable", f"the interpreter died ({what}) | {' / '.join(tail)[:400]}")
        elif ev == "missing":
            res.fail("uncatchable", "no result (the child interpreter ended before the case)")
        else:
            if r.get("type") == "HostileHang":
                res.fail("hang", r.get("msg", "")[:300])
            elif r.get("status") == "ok":
                succeeded = True
                if c.expect == "refuse":
                    res.warn("accepted", f"returned {r.get('value', '')[:200]}")
            else:
                why = py_allowed(r, c.allowed)
                if why:
                    res.fail("uncatchable", why)
                else:
                    if c.expect == "ok":
                        res.warn("baseline", f"{r.get('type')}: {r.get('msg', '')[:300]}")
                    if not c.no_message:
                        judge_message(res, r.get("msg", ""), [c.code] + c.echo, cli=False)
                        if r.get("msg_len", 0) > 4000:
                            res.warn("message", f"a message of {r['msg_len']} characters")
            if r.get("exit_rc") not in (None, 0):
                res.fail("uncatchable", f"the interpreter exited with {r['exit_rc']} after the case")
            if "panicked at" in err:
                m = re.search(r"panicked at [^\n]*\n?[^\n]*", err)
                res.fail("uncatchable", f"a Rust panic on stderr | {m.group(0).strip()[:300] if m else ''}")
            if "Fatal Python error" in err:
                res.fail("uncatchable", "Fatal Python error on stderr")
            if r.get("vlens_left"):
                res.fail("leak", f"virtual-lens folder left after the objects were dropped: {r['vlens_left'][0]}")
        post = snapshot(dirs[i])
        check_tree(res, pres[i], post, c.outputs, succeeded=succeeded, leaks=ev not in ("hang", "died"),
                   protect=c.protect)
        if ev not in ("hang",) and i in pids and not pid_alive(pids[i]):
            pass
        results[i] = res
    # folders of the child interpreters, which have all ended
    for pid in set(pids.values()):
        left = vlens_dirs(pid, ["/tmp"])
        if left:
            i = max(i for i, q in pids.items() if q == pid)
            if not any(f["class"] == "leak" for f in results[i].failures):
                results[i].fail("leak", f"virtual-lens folder of the ended interpreter (after its last case): {left[0]}")
    return [results[i] for i in range(len(cases))]


# ---------------------------------------------------------------------------------------
# Scheduling and the summary


def select_cases(cases: List[Case], args: argparse.Namespace) -> List[Case]:
    names = set()
    for c in cases:
        if c.name in names:
            raise SystemExit(f"battery: duplicate case name {c.name}")
        names.add(c.name)
    if args.fast:
        cases = [c for c in cases if c.fast]
    if args.filter:
        cases = [c for c in cases if args.filter in c.name]
    return cases


def units_of(cases: List[Case], batch: int) -> List[List[Case]]:
    units: List[List[Case]] = []
    py: Dict[str, List[Case]] = {}
    for c in cases:
        if c.kind == "py" and not c.isolate:
            py.setdefault(c.family, []).append(c)
        else:
            units.append([c])
    for fam, cs in py.items():
        for i in range(0, len(cs), batch):
            units.append(cs[i:i + batch])
    # long units first, so that the pool ends together
    def weight(u: List[Case]) -> float:
        return sum((c.timeout or 1) if c.kind != "py" else 0.2 for c in u) + (100 if u[0].kind == "custom" else 0)
    units.sort(key=weight, reverse=True)
    return units


def run_unit(unit: List[Case], ctx: Ctx) -> List[Result]:
    try:
        if unit[0].kind == "cli":
            return [run_cli_case(unit[0], ctx)]
        if unit[0].kind == "custom":
            c = unit[0]
            d = ctx.new_dir(c.name)
            t0 = time.monotonic()
            r = c.runner(c, ctx, d)
            r.seconds = time.monotonic() - t0
            r.detail.setdefault("dir", d)
            return [r]
        return run_py_batch(unit, ctx)
    except Exception as e:  # a bug of the battery itself: said, not hidden
        import traceback
        out = []
        for c in unit:
            r = Result(c.name, c.family, c.kind)
            r.fail("battery-error", f"{type(e).__name__}: {e} | {traceback.format_exc()[-600:]}")
            out.append(r)
        return out


def main() -> int:
    root_box: List[str] = []
    try:
        return run(root_box)
    finally:
        if root_box and os.path.isdir(root_box[0]) and not root_box[1:]:
            cleanup(root_box[0])


def run(root_box: List[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fast", action="store_true", help="the CI subset (about 770 cases, 1.5 min on 2 cores)")
    ap.add_argument("--binary", default=os.environ.get("ETLCAL_BINARY", os.path.join(REPO, "target", "debug", "etlcal")))
    ap.add_argument("--python", default=sys.executable, help="the interpreter of the Python cases (default: this one)")
    ap.add_argument("--json", metavar="OUT", help="write the summary and every failure as JSON")
    ap.add_argument("--json-all", action="store_true", help="with --json: every case's result, not only failures")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=20.0, help="seconds per case before it counts as a hang")
    ap.add_argument("--mem-limit-gb", type=float, default=4.0, help="address-space limit of every child process")
    ap.add_argument("--batch", type=int, default=80, help="Python cases per child interpreter")
    ap.add_argument("--filter", help="run only the cases whose name contains this text")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    ap.add_argument("--keep", action="store_true", help="keep the work directory")
    ap.add_argument("--workdir", help="where to make the work directory (default: the system's temp)")
    args = ap.parse_args()

    import hostile_cli
    import hostile_py

    if not os.path.isfile(args.binary):
        print(f"battery: no etlcal binary at {args.binary} (--binary or ETLCAL_BINARY)", file=sys.stderr)
        return 2
    root = tempfile.mkdtemp(prefix="etlcal-hostile-", dir=args.workdir)
    root_box.append(root)
    if args.keep:
        root_box.append("keep")
    ctx = Ctx(args, root)
    for sub in ("bin", "fx", "cases", "logs"):
        os.makedirs(os.path.join(root, sub))
    # A copy: a rebuild of the tree during the run cannot change the binary under test.
    shutil.copy2(args.binary, ctx.binary)

    t_all = time.monotonic()
    hostile_cli.build_fixtures(ctx)  # first: the mutation family reads the fixtures' contents
    t_fx = time.monotonic() - t_all
    cases = hostile_cli.cases(ctx) + hostile_py.cases(ctx)
    cases = select_cases(cases, args)
    if args.list:
        for c in cases:
            print(f"{c.kind:6} {c.family:18} {c.name}")
        print(f"{len(cases)} cases")
        return 0
    fx_before = snapshot(ctx.fx)
    vlens_before = set(glob.glob("/tmp/etl-vlens-*"))
    print(f"battery: {len(cases)} cases ({'fast' if args.fast else 'full'}), binary {args.binary}, "
          f"fixtures in {t_fx:.1f} s, work directory {root}", flush=True)

    results: List[Result] = []
    units = units_of(cases, args.batch)
    done = 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        futs = [pool.submit(run_unit, u, ctx) for u in units]
        for fut in concurrent.futures.as_completed(futs):
            for r in fut.result():
                results.append(r)
                done += 1
                for f in r.failures:
                    print(f"FAIL [{f['class']}] {r.name}: {f['what']}", flush=True)
    # The fixtures every case copied from, and the shared images of the datasets.
    global_res = Result("global/fixtures-intact", "global", "custom")
    check_tree(global_res, fx_before, snapshot(ctx.fx), [], succeeded=False, leaks=False)
    vl_after = set(glob.glob("/tmp/etl-vlens-*"))
    mine = set(ctx.children)
    for p in sorted(vl_after - vlens_before):
        m = re.match(r".*/etl-vlens-(\d+)-\d+$", p)
        if m and int(m.group(1)) in mine and not pid_alive(int(m.group(1))):
            if not any(p in f["what"] for r in results for f in r.failures):
                global_res.fail("leak", f"virtual-lens folder of an ended child: {p}")
    results.append(global_res)
    for f in global_res.failures:
        print(f"FAIL [{f['class']}] {global_res.name}: {f['what']}", flush=True)

    elapsed = time.monotonic() - t_all
    counts = {k: 0 for k in CLASSES}
    counts["battery-error"] = 0
    soft = {k: 0 for k in SOFT}
    failed_cases = 0
    for r in results:
        classes = {f["class"] for f in r.failures}
        for k in classes:
            counts[k] = counts.get(k, 0) + 1
        if classes:
            failed_cases += 1
        for k in {s["class"] for s in r.soft}:
            soft[k] += 1
    n = len(results) - 1
    held = n - sum(1 for r in results if r.failures and r.name != "global/fixtures-intact")
    print(f"battery: {n} cases in {elapsed:.0f} s: {held} held; data loss {counts['data-loss']}, "
          f"uncatchable {counts['uncatchable']}, hang {counts['hang']}, leak {counts['leak']}"
          + (f", battery errors {counts['battery-error']}" if counts["battery-error"] else "")
          + f" (soft: message {soft['message']}, accepted {soft['accepted']}, baseline {soft['baseline']})")
    if args.json:
        summary = {
            "mode": "fast" if args.fast else "full", "seed": args.seed, "binary": args.binary,
            "cases": n, "held": held, "seconds": round(elapsed, 1), "failures": counts, "soft": soft,
            "failed": [vars(r) for r in sorted(results, key=lambda r: r.name) if r.failures],
            "soft_findings": [{"name": r.name, "soft": r.soft, "detail": {k: r.detail.get(k) for k in ("rc", "stderr", "msg", "type")}}
                              for r in sorted(results, key=lambda r: r.name) if r.soft],
            "families": sorted({r.family for r in results}),
        }
        if args.json_all:
            summary["all"] = [vars(r) for r in sorted(results, key=lambda r: r.name)]
        with open(args.json, "w") as f:
            json.dump(summary, f, indent=1, default=str)
    if args.keep:
        print(f"battery: kept {root}")
    return 1 if any(counts[k] for k in CLASSES) or counts["battery-error"] else 0


def cleanup(root: str) -> None:
    def onerror(func, path, exc):  # read-only folders of the cases
        try:
            os.chmod(os.path.dirname(path), 0o755)
            os.chmod(path, 0o755)
            func(path)
        except OSError:
            pass
    shutil.rmtree(root, onerror=onerror)


if __name__ == "__main__":
    sys.exit(main())
