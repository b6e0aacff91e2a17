"""The probe matrix of issue 33: every case the issue lists, run for real, measured, and judged.

Each CLI case is its own ``python -m vidstyle`` process; the server cases are HTTP requests against real
``vidstyle annotate`` processes on free loopback ports; the concurrency and kill cases drive real processes
as the tests do (tests/test_annotate_concurrency.py, tests/test_parallel_orphans.py, tests/test_leftovers.py).
Every child runs under an address-space limit (``--limit-gb``, default 3) and a per-case timeout, so a
regression fails its case instead of taking the machine.

Measured per case: the exit code or HTTP status, wall seconds, the child's peak RSS (``wait4``'s
``ru_maxrss`` of that process, which also counts the image it was forked from: this process imports nothing
heavy before those cases; ``VmHWM`` of a server; the sum over a process tree for the kill cases) and the
file state (the output absent / the input unchanged / hidden leftovers in the directory). A case is
**clean** when it gives what the issue's goal asks: exit 2 with one ``vidstyle: error: <flag> ...`` line (or
a 4xx; 2xx for valid but large input), within 5 s, under 1 GB, and no half-written output; the
concurrency, kill and rerun cases have their own bars (no lost save, no surviving worker, no leftover).

Usage (inputs are read, never written: outputs go to a temporary directory)::

    python scripts/probe_reliability.py --pipeline pipelines/kickboxing --out probe.json [--quick]

prints a Markdown table grouped by the issue's items 1-7 and writes the results as JSON (``--out``).
Exit status: 0 when every case is clean, 1 otherwise.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import resource
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CLEAN_SECONDS = 5.0  # the bar for a bad input
CLEAN_MB = 1024.0  # ... and its memory
SURVIVAL = 5.0  # seconds a worker may outlive its killed parent

ITEMS = {
    0: "The probe itself (a case that could not be run)",
    1: "Unbounded or silently wrong numeric options",
    2: "Lost save with two annotate processes on one file",
    3: "Killed parallel run keeps working",
    4: "Leftovers",
    5: "The annotation server",
    6: "Imports coerce instead of refusing",
    7: "Tracebacks (exit 1)",
}


@dataclass
class Result:
    case: str
    item: int
    result: str = ""  # "exit 2", "HTTP 422", "1 win/trial", ...
    seconds: float = 0.0
    peak_mb: float = 0.0
    file_state: str = ""
    clean: bool = False
    expected: str = "exit 2"
    before: str = ""  # what the issue measured before the fixes
    detail: str = ""  # the error line, or why the case is not clean


# --------------------------------------------------------------------------------------------- processes
LIMIT_BYTES = 3 << 30


#: run as ``python -c LAUNCH limit cmd...``: set the address-space limit, then become ``cmd`` (same pid, so
#: ``wait4`` measures it); no ``preexec_fn``, which is unsafe while the probe runs threads
LAUNCH = ("import os, resource, sys; n = int(sys.argv[1]); resource.setrlimit(resource.RLIMIT_AS, (n, n)); "
          "os.execv(sys.argv[2], sys.argv[2:])")


def limited(cmd: list[str]) -> list[str]:
    """``cmd`` under the address-space limit (``--limit-gb``)."""
    return [sys.executable, "-c", LAUNCH, str(LIMIT_BYTES), *cmd]


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
            "COLUMNS": "200", "PYTHONWARNINGS": os.environ.get("PYTHONWARNINGS", "")}


def vidstyle_cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "vidstyle", *map(str, args)]


def run_measured(cmd: list[str], cwd: Path, timeout: float) -> dict:
    """Run ``cmd`` to its end (or kill it at ``timeout``): exit code, stdout, stderr, seconds, peak RSS (MB)
    of that process from ``wait4``."""
    with tempfile.TemporaryFile() as so, tempfile.TemporaryFile() as se:
        t0 = time.perf_counter()
        p = subprocess.Popen(limited(cmd), cwd=cwd, env=_env(), stdout=so, stderr=se, stdin=subprocess.DEVNULL,
                             start_new_session=True)
        code: int | str | None = None
        ru = None
        while True:
            pid, status, ru = os.wait4(p.pid, os.WNOHANG)
            if pid:
                code = os.waitstatus_to_exitcode(status)
                break
            if time.perf_counter() - t0 > timeout:
                os.killpg(p.pid, signal.SIGKILL)
                _, status, ru = os.wait4(p.pid, 0)
                code = "timeout"
                break
            time.sleep(0.005)
        seconds = time.perf_counter() - t0
        p.returncode = code if isinstance(code, int) else -9  # reaped here; Popen must not wait again
        so.seek(0)
        se.seek(0)
        return {"code": code, "seconds": seconds, "peak_mb": ru.ru_maxrss / 1024 if ru else 0.0,
                "stdout": so.read().decode("utf-8", "replace"), "stderr": se.read().decode("utf-8", "replace")}


def _sha(p: Path) -> str | None:
    return hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else None


def _listing(d: Path) -> dict[str, str | None]:
    """Every entry under ``d`` (recursive) with its file hash."""
    if not d.is_dir():
        return {}
    return {str(p.relative_to(d)): _sha(p) for p in sorted(d.rglob("*"))}


def _hidden(d: Path, ignore: tuple[str, ...] = (".lock",)) -> list[str]:
    """Hidden entries anywhere under ``d`` (writer temporaries, staging directories), except lock files."""
    if not d.is_dir():
        return []
    return sorted(str(p.relative_to(d)) for p in d.rglob(".*") if not p.name.endswith(ignore))


# --------------------------------------------------------------------------------------------- CLI cases
@dataclass
class CliCase:
    name: str
    item: int
    args: list[str]
    flag: str | None  # the error line starts with "vidstyle: error: <flag>" (None: any one-line error)
    before: str
    absent: list[str] = field(default_factory=list)  # outputs (relative to the case's directory) that must not appear
    unchanged: list[Path] = field(default_factory=list)  # inputs that must keep their bytes
    message: str | None = None  # must appear in the error line


def run_cli_case(c: CliCase, work: Path, timeout: float) -> Result:
    d = work / re.sub(r"[^A-Za-z0-9_.-]", "_", c.name)
    d.mkdir(parents=True)
    sums = {p: _sha(p) for p in c.unchanged}
    before = _listing(d)
    r = run_measured(vidstyle_cmd(*[a.replace("{d}", str(d)) for a in c.args]), d, timeout)
    lines = r["stderr"].strip().splitlines()
    problems = []
    if r["code"] != 2:
        problems.append(f"exit {r['code']}")
    if "Traceback" in r["stderr"]:
        problems.append("traceback")
    if len(lines) != 1 or not lines[0].startswith("vidstyle: error: "):
        problems.append(f"{len(lines)} stderr lines")
    elif c.flag and not lines[0].startswith(f"vidstyle: error: {c.flag}"):
        problems.append(f"does not name {c.flag}")
    if c.message and not any(c.message in ln for ln in lines):
        problems.append(f"no {c.message!r}")
    state = []
    written = [a for a in c.absent if (d / a).exists()]
    if written:
        state.append("written: " + ", ".join(written))
        problems.append("output written")
    changed = [p.name for p, s in sums.items() if _sha(p) != s]
    if changed:
        state.append("changed: " + ", ".join(changed))
        problems.append("input changed")
    new = sorted(set(_listing(d)) - set(before))
    if new and not written:
        state.append("new: " + ", ".join(new[:3]))
        problems.append("left files")
    if not state:
        state.append(("output absent" if c.absent else "no file written")
                     + (", input unchanged" if c.unchanged else ""))
    if r["seconds"] >= CLEAN_SECONDS:
        problems.append(f"{r['seconds']:.1f} s")
    if r["peak_mb"] >= CLEAN_MB:
        problems.append(f"{r['peak_mb']:.0f} MB")
    shutil.rmtree(d, ignore_errors=True)
    return Result(c.name, c.item, f"exit {r['code']}", r["seconds"], r["peak_mb"], "; ".join(state), not problems,
                  "exit 2", c.before, "; ".join(problems) or (lines[0][:200] if lines else ""))


def cli_cases(inp: dict[str, Path], scratch: Path) -> list[CliCase]:
    ds, lib, ann, video = inp["dataset"], inp["library"], inp["annotations"], inp["video"]
    clips, graph, poses, feats, vocab = inp["clips"], inp["graph"], inp["poses"], inp["features"], inp["vocab"]
    ev = ["evaluate", "augmg", "--dataset", ds, "--library", lib, "-a", ann, "-o", "{d}/augmg.json", "--jobs", "1"]
    pose = ["pose", video, "-a", ann, "-o", "{d}/p.json", "--jobs", "1"]
    aug = ["augment", "-g", graph, "-a", ann, "-l", clips, "-p", poses, "-o", "{d}/g.npz", "--jobs", "1"]
    train = ["train-recognizer", feats, "--annotations", ann, "--vocab", vocab, "-o", "{d}/r.joblib", "--jobs", "1"]
    match = ["match-pose", poses, "-l", clips, "-o", "{d}/m.json", "--jobs", "1"]
    serve = ["annotate", video, "-a", "{d}/a.json", "--no-browser", "--port", "0"]
    C = CliCase

    def S(*a) -> list[str]:  # short, as the table below reads
        return [str(x) for x in a]

    cases = [
        C("evaluate augmg --context 1000000000", 1, S(*ev, "--context", "1000000000"), "--context",
          "21.6 GB in 33 s, killed by the kernel", ["augmg.json"]),
        C("pose -a --context 1000000000", 1, S(*pose, "--context", "1000000000"), "--context",
          "spun for minutes", ["p.json"]),
        C("augment --context 1000000000", 1, S(*aug, "--context", "1000000000"), "--context",
          "spun for minutes", ["g.npz"]),
        C("train-recognizer --annotations --context 1000000000", 1, S(*train, "--context", "1000000000"),
          "--context", "spun for minutes", ["r.joblib"]),
        C("match-pose --views 100000", 1, S(*match, "--views", "100000"), "--views", "8 GB", ["m.json"]),
        C("augment --edges-per-side 1000000", 1, S(*aug, "--edges-per-side", "1000000"), "--edges-per-side",
          "ran 3 min", ["g.npz"]),
        C("augment --enhancement-cost nan", 1, S(*aug, "--enhancement-cost", "nan"), "--enhancement-cost",
          "exit 0, no enhancement edges", ["g.npz"]),
        C("augment --enhancement-cost -1", 1, S(*aug, "--enhancement-cost", "-1"), "--enhancement-cost",
          "accepted", ["g.npz"]),
        C("evaluate augmg --noise nan", 1, S(*ev, "--noise", "nan"), "--noise", "accepted, silently wrong",
          ["augmg.json"]),
        C("match-pose --fps nan", 1, S(*match, "--fps", "nan"), "--fps", "accepted, silently wrong", ["m.json"]),
        C("train-recognizer --window 0", 1, S(*train, "--window", "0"), "--window", "accepted, silently wrong",
          ["r.joblib"]),
        C("annotate --max-body-mb 1e-9", 1, S(*serve, "--max-body-mb", "1e-9"), "--max-body-mb",
          "served; every save then 413", ["a.json"]),
        C("annotate --classes ',,,'", 1, S(*serve, "--classes", ",,,"), "--classes", "accepted (no classes)",
          ["a.json"]),
        # item 4: a failed run leaves no empty output directory
        C("features <not a video> -o new dir", 4, S("features", scratch / "notes.mp4", "-o", "{d}/feat", "-j", "1"),
          None, "empty output directory left", ["feat"]),
        # item 7: the tracebacks
        C("features -o <an existing file>", 7, S("features", video, "-o", scratch / "exists.txt", "-j", "1"),
          str(scratch / "exists.txt"), "traceback (exit 1)", [], [scratch / "exists.txt"]),
        C("pose -o /proc/nope/p.json", 7, S("pose", video, "--frames", "0", "-o", "/proc/nope/p.json", "-j", "1"),
          "/proc/nope/p.json", "traceback (exit 1)"),
        C("evaluate augmg --k 0", 7, S(*ev, "--k", "0"), "--k", "traceback (exit 1)", ["augmg.json"]),
        C("annotate --max-body-mb nan", 7, S(*serve, "--max-body-mb", "nan"), "--max-body-mb",
          "traceback (exit 1)", ["a.json"]),
        C("train-recognizer --C nan", 7, S(*train, "--C", "nan"), "--C", "traceback (exit 1)", ["r.joblib"]),
        C("mocap info <0-frame BVH>", 7, S("mocap", "info", scratch / "zero.bvh"), None,
          "numpy warning and a vague message", [], [scratch / "zero.bvh"], message="no motion"),
        C("features <PNG renamed .mp4>", 7, S("features", scratch / "image.mp4", "-o", "{d}/fimg", "-j", "1"),
          None, "accepted as a one-frame video", ["fimg"], message="still image"),
    ]
    return cases


# --------------------------------------------------------------------------------------------- servers
def free_port(host: str = "127.0.0.1") -> int:
    with socket.socket() as s:
        s.bind((host, 0))
        return s.getsockname()[1]


def _vmhwm_mb(pid: int) -> float:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


class Server:
    """A real ``vidstyle annotate`` process on a free port; ``client`` carries Origin, Host and the page's
    token (and the secret, once known)."""

    def __init__(self, videos: list[Path], annotations: Path, cwd: Path, host: str = "127.0.0.1",
                 extra: list[str] = (), timeout: float = 60) -> None:
        import httpx

        self.port = free_port("127.0.0.1")
        self.host = host
        self.stderr = tempfile.TemporaryFile()  # noqa: SIM115 - open while the server runs, closed by stop()
        self.proc = subprocess.Popen(
            limited(vidstyle_cmd("annotate", *videos, "-a", annotations, "--no-browser", "--host", host, "--port",
                                 str(self.port), *extra)), cwd=cwd, env=_env(), stdout=subprocess.DEVNULL,
            stderr=self.stderr, stdin=subprocess.DEVNULL, start_new_session=True)
        self.hostport = f"{host}:{self.port}"
        base = f"http://127.0.0.1:{self.port}"
        self.origin = f"http://{self.hostport}"
        self.client = httpx.Client(base_url=base, headers={"Host": self.hostport, "Origin": self.origin},
                                   timeout=timeout)
        t0 = time.monotonic()
        while True:
            if self.proc.poll() is not None:
                raise RuntimeError(f"annotate exited {self.proc.returncode}: {self.err()[-500:]}")
            try:
                r = self.client.get("/")
                if r.status_code == 200:
                    self.page = r.text
                    break
            except httpx.TransportError:
                pass
            if time.monotonic() - t0 > 60:
                self.stop()
                raise RuntimeError("annotate did not start in 60 s")
            time.sleep(0.05)
        m = re.search(r'name="vidstyle-token" content="([^"]+)"', self.page)
        self.token = m.group(1) if m else ""
        self.client.headers["X-Vidstyle-Token"] = self.token

    def err(self) -> str:
        self.stderr.seek(0)
        return self.stderr.read().decode("utf-8", "replace")

    def peak_mb(self) -> float:
        return _vmhwm_mb(self.proc.pid)

    def stop(self) -> None:
        self.client.close()
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGTERM)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        self.stderr.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


def http_result(name: str, item: int, srv: Server, request, expect: str, before: str, files: Path,
                state_before: dict, extra_check=None) -> Result:
    """One request (``request(client) -> response``) timed; clean when its status is in ``expect``
    ("4xx", "2xx", "400", ...), within 5 s, the server under 1 GB and the annotations directory as it was."""
    t0 = time.perf_counter()
    try:
        r = request(srv.client)
        status, body = r.status_code, r.text[:200]
    except Exception as e:  # noqa: BLE001 - a dropped connection is a result too
        status, body = f"error {type(e).__name__}", str(e)[:200]
    seconds = time.perf_counter() - t0
    peak = srv.peak_mb()
    ok_status = isinstance(status, int) and (str(status) == expect or f"{str(status)[0]}xx" == expect
                                               or (expect == "4xx" and 400 <= status < 500))
    problems = [] if ok_status else [f"HTTP {status}"]
    extra = extra_check() if extra_check else None
    if extra:
        problems.append(extra)
    after = _listing(files)
    changed = sorted(k for k in set(after) | set(state_before) if after.get(k) != state_before.get(k)
                     and not k.endswith(".lock"))
    state = "annotations unchanged" if not changed else "changed: " + ", ".join(changed[:3])
    if changed and expect != "2xx":
        problems.append("file changed")
    if seconds >= CLEAN_SECONDS:
        problems.append(f"{seconds:.1f} s")
    if peak >= CLEAN_MB:
        problems.append(f"{peak:.0f} MB")
    return Result(name, item, f"HTTP {status}", seconds, peak, state, not problems, expect, before,
                  "; ".join(problems) or body)


def _nested(depth: int, inner: str = "1") -> str:
    return "[" * depth + inner + "]" * depth


def server_cases(inp: dict[str, Path], work: Path, results: list[Result]) -> None:
    """Items 5 and 6 on one server (a fresh annotations file holding one segment and one transition), item
    5's secret on a second one listening beyond loopback, item 4's symlink and mode on a third."""
    video = inp["video"]
    d = work / "server"
    d.mkdir()
    ann = d / "ann.json"
    with Server([video], ann, d) as srv:
        st = srv.client.get("/api/annotations").json()
        classes = st["classes"]
        a, b = classes[0], classes[1]
        r = srv.client.put("/api/annotations", json={"revision": st["revision"], "videos": [{
            "id": "0", "segments": [{"start": 10, "end": 30, "action": a}],
            "transitions": [{"frame": 50, "from_action": a, "to_action": b, "status": "accepted"}]}]})
        if r.status_code != 200:
            raise RuntimeError(f"cannot seed the annotations: {r.status_code} {r.text[:200]}")
        exports = {f: srv.client.get(f"/api/export/{f}?video=0").content for f in ("labelstudio", "via", "cvat")}
        state = _listing(d)
        def H(name, item, req, expect, before, check=None) -> None:
            results.append(http_result(name, item, srv, req, expect, before, d, state, check))

        # ---- item 5
        for label, idx in (("superscript two %C2%B2", "%C2%B2"), ("Arabic digit %D9%A3", "%D9%A3"),
                           ("full-width digit %EF%BC%93", "%EF%BC%93")):
            H(f"GET frame {label}", 5, lambda c, idx=idx: c.get(f"/api/videos/0/frames/{idx}"), "400",
              "500 (²)" if "B2" in idx else "accepted as a frame number")
        H('PUT id ["0"]', 5, lambda c: c.put("/api/annotations", json={"revision": 1, "videos": [
            {"id": ["0"], "segments": []}]}), "4xx", "500")
        deep = _nested(200_000).encode()
        H("PUT JSON nested 200000 deep", 5, lambda c: c.put("/api/annotations", content=deep,
                                                            headers={"Content-Type": "application/json"}),
          "4xx", "500 (RecursionError)")
        H("POST import native nested 200000 deep", 5, lambda c: c.post("/api/import/native?video=0", content=deep),
          "4xx", "500 (RecursionError)")
        ls = json.loads(exports["labelstudio"])
        seg = next(x for x in ls[0]["annotations"][0]["result"] if x["from_name"] == "actions")

        def ls_with(value: str, key: str = "start") -> bytes:
            seg["value"]["ranges"][0][key] = 123456789
            out = json.dumps(ls).replace("123456789", value).encode()
            seg["value"]["ranges"][0][key] = 11
            return out

        for value in ("Infinity", "1e400"):
            H(f"POST import labelstudio start {value}", 5,
              lambda c, v=value: c.post("/api/import/labelstudio?video=0", content=ls_with(v)), "4xx",
              "500 (OverflowError)")
        # 20k classes saved, 40k imported: linear, off the event loop (a GET during them stays quick)
        many = [f"class{i:06d}" for i in range(20_000)]
        results.append(_while_busy("PUT 20000 classes", 5, srv, lambda c: c.put(
            "/api/annotations", json={"revision": 1, "classes": classes + many}), "2xx",
            "6.3 s, server blocked", d))
        st = srv.client.get("/api/annotations").json()
        ls_many = json.loads(exports["labelstudio"])
        ls_many[0]["data"]["vidstyle_classes"] = [f"imp{i:06d}" for i in range(40_000)]
        data = json.dumps(ls_many).encode()
        results.append(_while_busy("POST import 40000 classes", 5, srv, lambda c: c.post(
            "/api/import/labelstudio?video=0", content=data), "2xx", "13.4 s, server blocked", d))
        n = (16 << 20) // 17 - 2000  # names of 12 characters + quotes and comma: a body just under 16 MiB
        big = json.dumps({"revision": st["revision"], "classes": classes + [f"b{i:011d}" for i in range(n)]}).encode()
        results.append(_while_busy(f"PUT 16 MiB body ({n} classes)", 5, srv, lambda c: c.put(
            "/api/annotations", content=big, headers={"Content-Type": "application/json"}), "2xx",
            "hours (quadratic)", d, bar=30.0))
        srv.client.put("/api/annotations", json={"revision": srv.client.get("/api/annotations").json()["revision"],
                                                 "classes": classes})
        state = _listing(d)
        # ---- item 6: strict imports
        via = json.loads(exports["via"])
        key_seg = next(k for k, md in via["metadata"].items() if len(md["z"]) == 2)
        dur = float(srv.client.get("/api/videos").json()[0]["duration"])

        def via_with(z_text: str) -> bytes:
            via["metadata"][key_seg]["z"] = [123456789]
            out = json.dumps(via).replace("[123456789]", z_text).encode()
            return out

        for label, z in ((f"out of range [0.5, {dur + 5:g}]", f"[0.5, {dur + 5:g}]"), ("NaN", "[NaN, 1.0]"),
                         ("Infinity", "[0.5, Infinity]"), ("reversed [1.0, 0.5]", "[1.0, 0.5]")):
            H(f"POST import via time {label}", 6, lambda c, z=z: c.post("/api/import/via?video=0",
                                                                         content=via_with(z)), "4xx",
              "clamped to valid frames (200)")
        for label, value in (("float 11.5", "11.5"), ('string "11"', '"11"'), ("boolean true", "true")):
            H(f"POST import labelstudio frame {label}", 6,
              lambda c, v=value: c.post("/api/import/labelstudio?video=0", content=ls_with(v)), "4xx",
              "truncated to a frame (200)")
        cvat = exports["cvat"].decode("utf-8")
        evil = re.sub(r"<\?xml[^>]*\?>", '<?xml version="1.0" encoding="utf-16"?>\n'
                      '<!DOCTYPE annotations [<!ENTITY x "Injected">]>', cvat, count=1)
        evil = evil.replace(f"<name>{a}</name>", "<name>&x;</name>", 1)
        H("POST import cvat UTF-16 internal entity", 6,
          lambda c: c.post("/api/import/cvat?video=0", content=evil.encode("utf-16")), "4xx",
          "entity expanded: a class injected (200)")
    # ---- item 5: a server beyond loopback needs the secret it printed, which the page does not carry
    d2 = work / "server_remote"
    d2.mkdir()
    t0 = time.perf_counter()
    with Server([video], d2 / "ann.json", d2, host="0.0.0.0") as srv:
        m = re.search(r"#key=([A-Za-z0-9_-]+)", srv.err())
        secret = m.group(1) if m else None
        no_secret = srv.client.put("/api/annotations", json={"revision": 0, "videos": []}).status_code
        get_no = srv.client.get("/api/annotations").status_code
        with_secret = srv.client.get("/api/annotations", headers={"X-Vidstyle-Secret": secret or ""}).status_code
        problems = []
        if not secret:
            problems.append("no secret printed")
        elif secret in srv.page:
            problems.append("secret served in the page")
        if no_secret != 401 or get_no != 401:
            problems.append(f"without the secret: PUT {no_secret}, GET {get_no}")
        if with_secret != 200:
            problems.append(f"with the secret: GET {with_secret}")
        results.append(Result("--host 0.0.0.0: API without the printed secret", 5,
                              f"HTTP {no_secret} (PUT), {get_no} (GET); {with_secret} with it",
                              time.perf_counter() - t0, srv.peak_mb(),
                              "nothing written" if not (d2 / "ann.json").exists() else "annotations written",
                              not problems and not (d2 / "ann.json").exists(), "401", 
                              "token in the page: anyone reaching the port can overwrite",
                              "; ".join(problems) or "secret only on stderr, never served"))
    # ---- item 4: the atomic writer keeps a symlink and the file's mode
    d3 = work / "server_link"
    (d3 / "data").mkdir(parents=True)
    real = d3 / "data" / "ann.json"
    shutil.copy(ann, real)
    os.chmod(real, 0o600)
    link = d3 / "ann.json"
    link.symlink_to(os.path.join("data", "ann.json"))
    with Server([video], link, d3) as srv:
        t0 = time.perf_counter()
        rev = srv.client.get("/api/annotations").json()["revision"]
        r = srv.client.put("/api/annotations", json={"revision": rev, "videos": [
            {"id": "0", "segments": [{"start": 60, "end": 70, "action": a}]}]})
        seconds = time.perf_counter() - t0
        peak = srv.peak_mb()
    mode = os.stat(real).st_mode & 0o777
    saved = json.loads(real.read_text())["revision"] if real.is_file() else None
    hidden = _hidden(d3)
    problems = []
    if r.status_code != 200 or saved != rev + 1:
        problems.append(f"save: HTTP {r.status_code}, revision {saved}")
    if not link.is_symlink():
        problems.append("the link became a regular file")
    if mode != 0o600:
        problems.append(f"mode {mode:o}")
    if hidden:
        problems.append("hidden: " + ", ".join(hidden))
    results.append(Result("save through a symlinked 0600 annotations file", 4, f"HTTP {r.status_code}", seconds,
                          peak, f"link kept: {link.is_symlink()}, mode {mode:o}, hidden: {hidden or 'none'}",
                          not problems, "200, link and 0600 kept", "link became a regular file, 0600 became 0644",
                          "; ".join(problems)))


def _while_busy(name: str, item: int, srv: Server, request, expect: str, before: str, files: Path,
                bar: float = CLEAN_SECONDS) -> Result:
    """``request`` timed while another client GETs /api/videos every 50 ms: the slowest of those answers
    (the event loop blocked by the request shows here) is reported."""
    import httpx

    stop = threading.Event()
    lat: list[float] = []

    def poll():
        with httpx.Client(base_url=str(srv.client.base_url), headers={"Host": srv.hostport}, timeout=120) as c:
            while not stop.is_set():
                t = time.perf_counter()
                c.get("/api/videos")
                lat.append(time.perf_counter() - t)
                time.sleep(0.05)

    th = threading.Thread(target=poll, daemon=True)
    th.start()
    time.sleep(0.1)
    t0 = time.perf_counter()
    try:
        r = request(srv.client)
        status = r.status_code
        body = r.text[:150]
    except Exception as e:  # noqa: BLE001
        status, body = f"error {type(e).__name__}", str(e)[:150]
    seconds = time.perf_counter() - t0
    stop.set()
    th.join(120)
    peak = srv.peak_mb()
    worst = max(lat) if lat else float("nan")
    problems = []
    if not (isinstance(status, int) and f"{str(status)[0]}xx" == expect):
        problems.append(f"HTTP {status}")
    if seconds >= bar:
        problems.append(f"{seconds:.1f} s")
    if not worst < 1.0:
        problems.append(f"a GET meanwhile took {worst:.2f} s (event loop blocked)")
    if peak >= CLEAN_MB:
        problems.append(f"{peak:.0f} MB")
    return Result(name, item, f"HTTP {status}", seconds, peak, f"slowest GET meanwhile {worst:.2f} s",
                  not problems, f"{expect} in < {bar:g} s, loop free", before, "; ".join(problems) or body)


#: remux argv[1] into argv[2] with the index (moov) at the front (run in a child: PyAV stays out of the probe)
REMUX_FASTSTART = """
import sys, av
with av.open(sys.argv[1]) as i, av.open(sys.argv[2], "w", options={"movflags": "faststart"}) as o:
    s = i.streams.video[0]
    out = o.add_stream_from_template(s)
    for p in i.demux(s):
        if p.dts is not None:
            p.stream = out
            o.mux(p)
"""


def truncated_video_case(inp: dict[str, Path], work: Path) -> Result:
    """Item 7: an mp4 with its index (moov) at the front, cut in half: the server counts only the frames
    that decode, and the last one it announces is served (before: one too many, the last a 500)."""
    d = work / "cut"
    d.mkdir()
    whole = d / "whole.mp4"
    subprocess.run([sys.executable, "-c", REMUX_FASTSTART, str(inp["video"]), str(whole)], check=True, env=_env())
    raw = whole.read_bytes()
    if raw[4:8] != b"ftyp" or b"moov" not in raw[:64 << 10]:
        return Result("mp4 (moov first) cut in half: last frame", 7, "not reproduced", 0, 0, "", False, "200",
                      detail="could not write an mp4 with its index at the front")
    cut = d / "cut.mp4"
    cut.write_bytes(raw[: len(raw) // 2])
    whole.unlink()
    t0 = time.perf_counter()
    try:
        with Server([cut], d / "ann.json", d) as srv:
            info = srv.client.get("/api/videos").json()[0]
            n = info["frames"]
            last = srv.client.get(f"/api/videos/0/frames/{n - 1}").status_code
            past = srv.client.get(f"/api/videos/0/frames/{n}").status_code
            seconds = time.perf_counter() - t0
            peak = srv.peak_mb()
    except RuntimeError as e:  # refused at start: also clean when it names the file
        seconds = time.perf_counter() - t0
        msg = str(e)
        ok = "exited 2" in msg and "cut.mp4" in msg
        return Result("mp4 (moov first) cut in half: last frame", 7, msg.split(":")[0], seconds, 0.0,
                      "no file written", ok, "200 for the last frame (or exit 2)", "last frame 500",
                      msg[-200:])
    problems = [] if last == 200 and past == 404 else [f"frame {n - 1}: {last}, frame {n}: {past}"]
    if seconds >= CLEAN_SECONDS * 2:
        problems.append(f"{seconds:.1f} s")
    return Result("mp4 (moov first) cut in half: last frame", 7, f"HTTP {last} (frame {n - 1} of {n}), {past} past it",
                  seconds, peak, "-", not problems, "200 last, 404 past", "one frame too many; the last gave 500",
                  "; ".join(problems) or f"{n} decodable frames announced")


# --------------------------------------------------------------------------------------------- item 2
def concurrency_cases(inp: dict[str, Path], work: Path, trials: int) -> list[Result]:
    """Two ``annotate`` processes on one file: per trial both read the state and both save from that revision
    at once; exactly one may win, the loser (409) reloads and saves its change again. Then an outside write:
    the stale page gets 409 and, after reloading, saves."""
    d = work / "concurrency"
    d.mkdir()
    ann = d / "ann.json"
    out: list[Result] = []
    t0 = time.perf_counter()
    with Server([inp["video"]], ann, d) as s1, Server([inp["video"]], ann, d) as s2:
        cls = s1.client.get("/api/annotations").json()["classes"][0]
        barrier = threading.Barrier(2)
        log: list[list[tuple]] = [[], []]

        def worker(k: int, srv: Server) -> None:
            try:
                for t in range(trials):
                    barrier.wait(60)
                    st = srv.client.get("/api/annotations").json()
                    seg = {"start": 4 * t + 2 * k, "end": 4 * t + 2 * k + 1, "action": cls}
                    body = {"revision": st["revision"],
                            "videos": [{"id": "0", "segments": st["videos"][0]["segments"] + [seg]}]}
                    barrier.wait(60)
                    r = srv.client.put("/api/annotations", json=body)
                    log[k].append((r.status_code, st["revision"]))
                    barrier.wait(60)
                    if r.status_code == 409:
                        st = srv.client.get("/api/annotations").json()
                        r = srv.client.put("/api/annotations", json={"revision": st["revision"], "videos": [
                            {"id": "0", "segments": st["videos"][0]["segments"] + [seg]}]})
                        log[k].append(("retry", r.status_code))
                    barrier.wait(60)
            except Exception as e:  # noqa: BLE001
                log[k].append(("error", repr(e)))
                barrier.abort()

        ths = [threading.Thread(target=worker, args=(k, s)) for k, s in enumerate((s1, s2))]
        for th in ths:
            th.start()
        for th in ths:
            th.join(600)
        seconds = time.perf_counter() - t0
        firsts = [[x for x in lg if x[0] != "retry"] for lg in log]
        errors = [x for lg in log for x in lg if x[0] == "error"]
        pairs = [(firsts[0][t][0], firsts[1][t][0]) for t in range(min(map(len, firsts)))]
        double = sum(1 for p in pairs if p == (200, 200))
        one = sum(1 for p in pairs if sorted(p) == [200, 409])
        retry_fail = [x for lg in log for x in lg if x[0] == "retry" and x[1] != 200]
        doc = json.loads(ann.read_text())
        starts = sorted(s["start"] for s in doc["videos"][0]["segments"])
        want = sorted(4 * t + 2 * k for t in range(trials) for k in (0, 1))
        lost = len(set(want) - set(starts))
        problems = []
        if errors:
            problems.append(f"errors: {errors[:2]}")
        if double:
            problems.append(f"{double} trials with two 200s for one revision")
        if one != trials:
            problems.append(f"{trials - one} trials without exactly one 200 and one 409: {pairs[:5]}")
        if retry_fail:
            problems.append(f"{len(retry_fail)} retries failed")
        if lost or doc["revision"] != 2 * trials:
            problems.append(f"{lost} changes lost, revision {doc['revision']} (want {2 * trials})")
        peak = max(s1.peak_mb(), s2.peak_mb())
        out.append(Result(f"two servers, one file: {trials} concurrent trials", 2,
                          f"{one}/{trials} trials one 200 + one 409", seconds, peak,
                          f"{len(starts)}/{2 * trials} segments saved, revision {doc['revision']}", not problems,
                          "one winner per revision, no lost save", "both 200 for one revision; a change lost in 3 of 4",
                          "; ".join(problems)))
        # an outside write, then the stale page: 409, reload, save
        t0 = time.perf_counter()
        st = s1.client.get("/api/annotations").json()
        doc = json.loads(ann.read_text())
        doc["videos"][0]["segments"] = doc["videos"][0]["segments"][:-1]
        doc["revision"] += 5
        tmp = ann.with_name("outside.json")
        tmp.write_text(json.dumps(doc))
        os.replace(tmp, ann)
        stale = s1.client.put("/api/annotations", json={"revision": st["revision"], "videos": [
            {"id": "0", "segments": st["videos"][0]["segments"]}]})
        reloaded = s1.client.get("/api/annotations").json()
        again = s1.client.put("/api/annotations", json={"revision": reloaded["revision"], "videos": [
            {"id": "0", "segments": reloaded["videos"][0]["segments"] + [
                {"start": 4 * trials + 10, "end": 4 * trials + 12, "action": cls}]}]})
        seconds = time.perf_counter() - t0
        final = json.loads(ann.read_text())
        ok = (stale.status_code == 409 and reloaded["revision"] == doc["revision"] and again.status_code == 200
              and final["revision"] == doc["revision"] + 1)
        out.append(Result("outside write, then the open page saves", 2,
                          f"HTTP {stale.status_code}, reload, HTTP {again.status_code}", seconds, s1.peak_mb(),
                          f"revision {final['revision']} (outside wrote {doc['revision']})", ok,
                          "409 then 200 after a reload", "409 forever (the store never re-read the file)",
                          "" if ok else f"reload saw revision {reloaded['revision']}"))
    hidden = _hidden(d)
    if hidden:
        out[0].clean = False
        out[0].detail += f"; hidden: {hidden}"
    return out


# --------------------------------------------------------------------------------------------- items 3, 4
def _tree_peak(proc: subprocess.Popen, stop: threading.Event, peak: list[float], kids: set) -> None:
    import psutil

    try:
        root = psutil.Process(proc.pid)
    except psutil.NoSuchProcess:
        return
    while not stop.is_set():
        try:
            procs = [root, *root.children(recursive=True)]
            kids.update(procs[1:])
            rss = sum(p.memory_info().rss for p in procs if p.is_running())
            peak[0] = max(peak[0], rss / (1 << 20))
        except psutil.Error:
            pass
        time.sleep(0.1)


def _alive(p) -> bool:
    import psutil

    try:
        return p.is_running() and p.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def _start(cmd: list[str], cwd: Path) -> subprocess.Popen:
    return subprocess.Popen(limited(cmd), cwd=cwd, env=_env(), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL, start_new_session=True)


def killed_features_jobs2(inp: dict[str, Path], work: Path, deadline: float = 300) -> Result:
    """Item 3: kill -9 of ``features --jobs 2`` once its first output is written: no worker may survive 5 s,
    no file may appear afterwards."""
    d = work / "kill_features2"
    out = d / "out"
    d.mkdir()
    videos = inp["short_videos"][:6]
    proc = _start(vidstyle_cmd("features", *videos, "--jobs", "2", "-o", out), d)
    stop, peak, kids = threading.Event(), [0.0], set()
    th = threading.Thread(target=_tree_peak, args=(proc, stop, peak, kids), daemon=True)
    th.start()
    t0 = time.monotonic()
    while not (out.is_dir() and any(p.suffix == ".npz" and not p.name.startswith(".") for p in out.iterdir())):
        if proc.poll() is not None or time.monotonic() - t0 > deadline:
            stop.set()
            proc.kill()
            return Result("kill -9 features --jobs 2", 3, "not reproduced", 0, peak[0], "", False,
                          "no worker after 5 s", detail=f"run ended (exit {proc.returncode}) before its first output")
        time.sleep(0.05)
    stop.set()
    th.join()
    import psutil

    try:
        kids.update(psutil.Process(proc.pid).children(recursive=True))
    except psutil.Error:
        pass
    before = sorted(os.listdir(out))
    t_kill = time.perf_counter()
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    while any(_alive(k) for k in kids) and time.perf_counter() - t_kill < SURVIVAL:
        time.sleep(0.05)
    gone_after = time.perf_counter() - t_kill
    survivors = [k.pid for k in kids if _alive(k)]
    for k in kids:
        if _alive(k):
            k.kill()
    time.sleep(1.0)
    after = sorted(os.listdir(out))
    added = sorted(set(after) - set(before))
    problems = []
    if not kids:
        problems.append("no worker seen")
    if survivors:
        problems.append(f"{len(survivors)} workers alive {SURVIVAL:g} s after the kill")
    if added:
        problems.append("written after the kill: " + ", ".join(added))
    return Result("kill -9 features --jobs 2", 3, f"{len(kids)} workers, {len(survivors)} survived",
                  gone_after, peak[0], f"{len([n for n in before if not n.startswith('.')])}/{len(videos)} outputs at "
                  f"the kill, {len(added)} after", not problems, "no worker after 5 s, no file after",
                  "workers reparented to init at 95 % CPU, writing .npz for 90 s+", "; ".join(problems))


def _running_tasks(dask_worker) -> int:
    return len(dask_worker.active_threads)


def killed_features_dask(inp: dict[str, Path], work: Path, deadline: float = 300) -> Result:
    """Item 3 on a Dask cluster: kill -9 of ``features --scheduler`` once its first output is written; the
    cluster's workers (not ours to kill) stop its running calls within 5 s and write nothing more (a call
    already renaming its finished temporary at the kill may complete that one file)."""
    from dask import distributed

    d = work / "kill_dask"
    out = d / "out"
    d.mkdir()
    videos = inp["short_videos"][:6]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=50) as cluster, distributed.Client(cluster) as client:
        proc = _start(vidstyle_cmd("features", *videos, "-o", out, "--scheduler", cluster.scheduler_address), d)
        stop, peak, kids = threading.Event(), [0.0], set()
        th = threading.Thread(target=_tree_peak, args=(proc, stop, peak, kids), daemon=True)
        th.start()
        t0 = time.monotonic()
        while not (out.is_dir() and any(p.suffix == ".npz" and not p.name.startswith(".") for p in out.iterdir())
                   and sum(client.run(_running_tasks).values()) > 0):
            if proc.poll() is not None or time.monotonic() - t0 > deadline:
                stop.set()
                proc.kill()
                return Result("kill -9 features --scheduler (Dask)", 3, "not reproduced", 0, peak[0], "", False,
                              "no running task after 5 s", detail=f"run ended (exit {proc.returncode}) mid-way?")
            time.sleep(0.05)
        stop.set()
        th.join()
        before = sorted(os.listdir(out))
        t_kill = time.perf_counter()
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        while sum(client.run(_running_tasks).values()) and time.perf_counter() - t_kill < SURVIVAL:
            time.sleep(0.05)
        stopped = time.perf_counter() - t_kill
        running = sum(client.run(_running_tasks).values())
        time.sleep(1.0)
        after = sorted(os.listdir(out))
    finishing = {re.sub(r"^\.(.+)\.(?:\d+-)?[a-z0-9_]{8}\.tmp(\.npz)$", r"\1\2", n) for n in before if n.startswith(".")}
    added = sorted(n for n in set(after) - set(before) if n not in finishing)
    problems = []
    if running:
        problems.append(f"{running} tasks still running {SURVIVAL:g} s after the kill")
    if added:
        problems.append("written after the kill: " + ", ".join(added) + f" (listed at the kill: {before})")
    return Result("kill -9 features --scheduler (Dask)", 3, f"{running} tasks running after the kill", stopped,
                  peak[0], f"{len([n for n in before if not n.startswith('.')])}/{len(videos)} outputs at the kill "
                  f"({len(finishing)} being written), {len(added)} after", not problems,
                  "tasks stopped within 5 s, no file after",
                  "(the issue probed loky; each running call finished and wrote its .npz)", "; ".join(problems))


def killed_then_rerun(name: str, cmd: list[str], d: Path, out_parent: Path, seen, done, deadline: float,
                      rerun_timeout: float, before: str) -> Result:
    """Start ``cmd``, kill -9 it as soon as ``seen()`` (a partial file / staging directory is there), then run
    ``cmd`` again to its end: nothing hidden may be left in ``out_parent``."""
    proc = _start(cmd, d)
    t0 = time.monotonic()
    caught = None
    while True:
        caught = seen()
        if caught or proc.poll() is not None or time.monotonic() - t0 > deadline:
            break
        time.sleep(0.001)
    if proc.poll() is None:
        os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    try:  # its workers, if any, are ended by their watchdog; give them the 5 s
        os.killpg(proc.pid, 0)
        time.sleep(SURVIVAL)
    except ProcessLookupError:
        pass
    left = _hidden(out_parent)
    r = run_measured(cmd, d, rerun_timeout)
    after = _hidden(out_parent)
    problems = []
    if r["code"] != 0:
        problems.append(f"rerun exit {r['code']}: {r['stderr'].strip().splitlines()[-1:]}")
    if not done():
        problems.append("the rerun's output is missing")
    if after:
        problems.append("left after the rerun: " + ", ".join(after))
    note = (f"kill left {', '.join(left)}" if left else
            "kill left nothing hidden" + ("" if caught else " (the kill did not catch a partial file)"))
    return Result(name, 4, f"rerun exit {r['code']}", r["seconds"], r["peak_mb"],
                  f"{note}; after the rerun: {', '.join(after) or 'nothing hidden'}", not problems,
                  "no leftover after kill + rerun", before, "; ".join(problems))


def leftover_cases(inp: dict[str, Path], work: Path) -> list[Result]:
    out: list[Result] = []
    d = work / "kill_features1"
    d.mkdir()
    feat = d / "features"
    videos = inp["short_videos"][:3]

    def partial():
        try:
            return [n for n in os.listdir(feat) if n.startswith(".") and ".tmp" in n]
        except FileNotFoundError:
            return []

    out.append(killed_then_rerun(
        "kill -9 features --jobs 1 while writing, rerun", vidstyle_cmd("features", *videos, "--jobs", "1", "-o", feat),
        d, feat, partial, lambda: all((feat / (Path(v).stem + ".npz")).is_file() for v in videos), 300, 300,
        "hidden .p00_lowkick_front.*.tmp.npz left in out/features for good"))
    d = work / "kill_library"
    d.mkdir()
    lib = d / "lib"
    out.append(killed_then_rerun(
        "kill -9 demo make-library while building, rerun",
        vidstyle_cmd("demo", "make-library", "-o", lib, "--performers", "2", "--action-seconds", "2", "--jobs", "1",
                     "--overwrite"),
        d, d, lambda: [n for n in os.listdir(d) if n.startswith(".lib.")], lambda: (lib / "library.json").is_file(),
        300, 600, ".kl.*.tmp/ left beside the library"))
    return out


# --------------------------------------------------------------------------------------------- inputs
FIRST_FRAME_PNG = """
import sys, av, cv2
with av.open(sys.argv[1]) as c:
    f = next(c.decode(video=0)).to_ndarray(format="bgr24")
open(sys.argv[2], "wb").write(cv2.imencode(".png", f)[1].tobytes())
"""


def inputs(pipeline: Path, scratch: Path) -> dict[str, Path]:
    pipeline = pipeline.resolve()
    o = pipeline / "out"
    params = (pipeline / "params.yaml").read_text() if (pipeline / "params.yaml").is_file() else ""
    m = re.search(r"^\s*annotations:\s*(\S+)", params, re.MULTILINE)
    ann = (pipeline / (m.group(1) if m else "../../annotations/demo.json")).resolve()
    doc = json.loads(ann.read_text())
    first = (ann.parent / doc["videos"][0]["path"]).resolve()
    stem = first.stem
    vids = sorted((o / "dataset" / "videos").glob("p*_*_front.mp4"))
    short = [v for v in vids if "perf" not in v.name]
    inp = {"pipeline": pipeline, "dataset": o / "dataset", "library": o / "augmg" / "library",
           "clips": o / "augmg" / "library" / "clips", "annotations": ann, "video": first,
           "graph": o / "graph" / "graph.npz", "poses": o / "poses_blazepose" / f"{stem}.poses.json",
           "features": o / "features" / f"{stem}.npz", "vocab": o / "models" / "vocab.npz",
           "short_videos": short}
    missing = [str(v) for k, v in inp.items() if k != "short_videos" and not Path(v).exists()]
    if missing or len(short) < 6:
        raise SystemExit(f"probe: inputs missing under {pipeline} (run the pipeline first): {missing or 'videos'}")
    # small synthetic inputs the item-4/7 cases need
    (scratch / "exists.txt").write_text("a file, not a directory\n")
    (scratch / "notes.mp4").write_text("this is a text file, not a video\n" * 40)
    (scratch / "zero.bvh").write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Zrotation Xrotation "
                                      "Yrotation\n  End Site\n  {\n    OFFSET 0 1 0\n  }\n}\nMOTION\nFrames: 0\n"
                                      "Frame Time: 0.05\n")
    # a PNG of the first frame, named .mp4; in a child, so that this process stays small (a child's ru_maxrss
    # counts the image it was forked from)
    subprocess.run([sys.executable, "-c", FIRST_FRAME_PNG, str(first), str(scratch / "image.mp4")], check=True,
                   env=_env())
    return inp


# --------------------------------------------------------------------------------------------- report
def esc(s) -> str:
    return str(s).replace("|", "\\|").replace("\n", " ")


def table(results: list[Result]) -> str:
    rows = ["| case | issue item | result | seconds | peak MB | file state | clean? |",
            "|---|---|---|---:|---:|---|---|"]
    for item in sorted(ITEMS):
        rs = [r for r in results if r.item == item]
        if not rs:
            continue
        rows.append(f"| **{item}. {ITEMS[item]}** | | | | | | |")
        for r in rs:
            flag = "yes" if r.clean else f"**NO**: {esc(r.detail)}"
            rows.append(f"| {esc(r.case)} | {item} | {esc(r.result)} | {r.seconds:.2f} | {r.peak_mb:.0f} | "
                        f"{esc(r.file_state)} | {flag} |")
    n = sum(r.clean for r in results)
    rows.append(f"\n{n} of {len(results)} cases clean.")
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pipeline", type=Path, default=ROOT / "pipelines" / "kickboxing",
                    help="a finished pipeline run (its out/ and params.yaml): the inputs, read only")
    ap.add_argument("--out", type=Path, help="write the results as JSON here")
    ap.add_argument("--quick", action="store_true",
                    help="10 concurrency trials instead of 100, and no Dask kill case")
    ap.add_argument("--only", default="", help="comma-separated groups: cli,server,concurrency,kill,leftovers,cut")
    ap.add_argument("--timeout", type=float, default=60.0, help="per-case timeout (s) of a CLI case")
    ap.add_argument("--limit-gb", type=float, default=3.0, help="address-space limit of every child (GB)")
    args = ap.parse_args(argv)
    global LIMIT_BYTES
    LIMIT_BYTES = int(args.limit_gb * (1 << 30))
    groups = set(filter(None, args.only.split(","))) or {"cli", "server", "concurrency", "kill", "leftovers", "cut"}
    results: list[Result] = []
    with tempfile.TemporaryDirectory(prefix="vidstyle-probe-") as tmp:
        work = Path(tmp)
        scratch = work / "inputs"
        scratch.mkdir()
        inp = inputs(args.pipeline, scratch)

        def step(label, fn):
            t = time.perf_counter()
            print(f"probe: {label} ...", file=sys.stderr, flush=True)
            try:
                fn()
            except Exception as e:  # noqa: BLE001 - a probe that breaks is a result, not a crash
                results.append(Result(f"{label}: probe failed", 0, "error", 0, 0, "", False, detail=repr(e)[:300]))
            print(f"probe: {label} done in {time.perf_counter() - t:.0f} s", file=sys.stderr, flush=True)

        if "cli" in groups:
            step("CLI cases", lambda: results.extend(run_cli_case(c, work / "cli", args.timeout)
                                                     for c in cli_cases(inp, scratch)))
        if "leftovers" in groups:  # early: its reruns' peak RSS is measured while this process is small
            step("kill and rerun", lambda: results.extend(leftover_cases(inp, work)))
        if "server" in groups:
            step("server cases", lambda: server_cases(inp, work, results))
        if "cut" in groups:
            step("truncated video", lambda: results.append(truncated_video_case(inp, work)))
        if "concurrency" in groups:
            step("concurrency", lambda: results.extend(concurrency_cases(inp, work, 10 if args.quick else 100)))
        if "kill" in groups:
            step("kill features --jobs 2", lambda: results.append(killed_features_jobs2(inp, work)))
            if not args.quick:  # last: it brings dask.distributed into this process
                step("kill features on Dask", lambda: results.append(killed_features_dask(inp, work)))
    for r in results:
        r.seconds = round(r.seconds, 3)
        r.peak_mb = round(r.peak_mb, 1)
    print(table(results))
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps({"pipeline": str(args.pipeline), "quick": args.quick,
                                        "clean_seconds": CLEAN_SECONDS, "clean_mb": CLEAN_MB,
                                        "limit_gb": args.limit_gb,
                                        "probe_peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                                        "cases": [asdict(r) for r in results]},
                                       indent=2) + "\n")
    return 0 if results and all(r.clean for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
