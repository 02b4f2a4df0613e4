"""Fuzz the readers and the command line for a time budget, and report distinct crash sites.

Not a test: from the repository root (package installed, ``hypothesis`` installed: the checks
are those of ``tests/test_fuzz_properties.py``) run

    python benchmarks/fuzz.py [--seconds 60] [--out /tmp/ncperf-fuzz] [--targets gcode,cl,...]
                              [--engine both|random|atheris] [--seed 0]

and read the table. Targets: ``gcode`` (``.ngc`` LinuxCNC, ``.nc``, ``.mpf`` Siemens: extract
and analyze), ``cl`` (APT CL data), ``csv`` and ``shdr`` (traces), ``machine`` (machine TOML,
then a small program analyzed with it) and ``cli`` (``ncperf analyze/profile/compare/diagnose/
calibrate`` in process). Inputs come from ``tests/fuzz_inputs.py``: grammars, mutations of the
bundled examples and presets, random bytes.

The property (as in the tests): a reader raises ``NcperfError`` or returns finite numbers; the
command line exits 0/1/2 with one line on failure, no control character, no output left by a
failed run, strict JSON. Every input runs in this process under a memory cap (RLIMIT_AS,
``--memory-gib``, 4 by default) and a time limit (SIGALRM, ``--timeout`` s). A finding is
anything else: an exception (deduplicated by its type and the innermost frame in ``core/``,
``adapters/``, ``plugins/`` or ``refvm/``), a time-out or memory error (same key), or a
property violation (by the rule it breaks). NumPy ``RuntimeWarning``s raised in project code
are listed apart (not crashes, but where NaN or overflow is made).

Each new finding gets a folder under ``--out``: the input file(s) as found, a line-minimized
copy (single-file targets), the traceback, and the command to replay it
(``--replay TARGET:INDEX`` regenerates input INDEX of a random run with the same ``--seed``).

Engines: ``random`` drives the generators with ``random.Random``; ``atheris`` (coverage-guided
libFuzzer; ``pip install atheris`` installed atheris 3.0.0 from a wheel on this Linux x86-64
machine with CPython 3.11) mutates bytes of the file targets, starting from a corpus of
generated inputs, with the project's functions instrumented. libFuzzer owns the process it
runs in (it exits at the end), so each atheris run is a forked child that writes its findings
to ``--out``; ``both`` (the default) gives each file target half its seconds per engine, the
command line all of them to ``random``. Without atheris (not installed, or another platform),
``both`` runs ``random`` alone and says so.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import os
import random
import re
import resource
import shutil
import signal
import sys
import tempfile
import time
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # one BLAS thread: less address space

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests import fuzz_inputs as F  # noqa: E402
from tests import test_fuzz_properties as P  # noqa: E402

PROJECT = tuple(str(ROOT / d) + os.sep for d in ("core", "adapters", "plugins", "refvm"))
TARGETS = ("gcode", "cl", "csv", "shdr", "machine", "cli")
FILE_TARGETS = TARGETS[:-1]


class Timeout(BaseException):
    """One input ran past ``--timeout`` (a BaseException: ``except Exception`` in the code
    under test does not swallow it). ``sample`` is the stack one second earlier."""

    def __init__(self, message: str, sample: list[Any]) -> None:
        super().__init__(message)
        self.sample = sample


#: The time limit runs in two steps: a sample of the stack a second before the end, then the
#: Timeout. A hang's site is the innermost project frame that is on the stack both times (the
#: same frame object, kept alive by the sample: the function whose loop does not end).
_ALARM: dict[str, Any] = {"sample": None, "rest": 0.0}


def _stack(frame: Any) -> list[Any]:
    out = []
    while frame is not None:
        out.append(frame)
        frame = frame.f_back
    return out


def arm(seconds: float) -> None:
    first = seconds - 1 if seconds > 2 else seconds / 2
    _ALARM["sample"], _ALARM["rest"] = None, seconds - first
    signal.setitimer(signal.ITIMER_REAL, first)


def disarm() -> None:
    signal.setitimer(signal.ITIMER_REAL, 0)
    _ALARM["sample"] = None  # the sampled frames hold the input's memory


def _alarm(signum: int, frame: Any) -> None:
    if _ALARM["sample"] is None:
        _ALARM["sample"] = _stack(frame)
        signal.setitimer(signal.ITIMER_REAL, _ALARM["rest"])
        return
    raise Timeout("input took longer than the time limit", _ALARM["sample"])


# ----------------------------------------------------------------------------- inputs
@dataclass
class Input:
    """One input: files (name -> bytes) and, for the command line, the case and a seed for
    the edits the harness makes while running it."""

    files: dict[str, bytes]
    options: dict[str, Any] = field(default_factory=dict)
    case: F.CliCase | None = None
    run_seed: int = 0


def make_input(target: str, rng: random.Random) -> Input:
    """One generated input of ``target`` (the random engine)."""
    r = rng.random()
    if target == "gcode":
        ext = rng.choice(F.GCODE_EXTENSIONS)
        if r < 0.45:
            data = F.to_bytes(rng, F.gcode_program(rng, F.DIALECT_OF[ext], rng.randint(4, 60)))
        elif r < 0.9:
            data = F.gcode_mutant(rng, F.gcode_seeds(max_bytes=20000), rounds=rng.randint(1, 6))
        else:
            data = F.random_bytes(rng, 2000)
        opts = {
            "machine": rng.choice(sorted(P.MACHINES)),
            "dialect": rng.choice((None, None, None, "fanuc", "siemens", "linuxcnc")),
            "block_delete": rng.random() < 0.1,
        }
        return Input({f"p{ext}": data}, opts)
    if target == "cl":
        ext = rng.choice(F.CL_EXTENSIONS)
        if r < 0.5:
            data = F.to_bytes(rng, F.cl_program(rng, rng.randint(4, 60)))
        elif r < 0.9:
            data = F.cl_mutant(rng, rounds=rng.randint(1, 6))
        else:
            data = F.random_bytes(rng, 2000)
        return Input({f"p{ext}": data}, {"machine": rng.choice(sorted(P.MACHINES))})
    if target in ("csv", "shdr"):
        text = F.csv_trace(rng, 60) if target == "csv" else F.shdr_trace(rng, 60)
        if r < 0.6:
            data = text.encode()
        elif r < 0.9:
            data = F.mutate_bytes(rng, text.encode(), F.TRACE_TOKENS, rng.randint(1, 4))
        else:
            data = F.random_bytes(rng, 1000)
        units = rng.choice((None, "mm", "inch"))
        return Input({f"t.{target}": data}, {"units": units})
    if target == "machine":
        if r < 0.95:
            return Input({"m.toml": F.machine_toml(rng, rounds=rng.randint(1, 5)).encode()})
        return Input({"m.toml": F.random_bytes(rng, 600)})
    case = F.cli_case(rng)
    return Input(
        {name: data for name, data in case.programs}, case=case, run_seed=rng.getrandbits(32)
    )


def bytes_input(target: str, data: bytes) -> Input:
    """An input of a file target made of raw bytes (the atheris engine): for G-code and CL
    data the first byte picks the extension."""
    if target == "gcode":
        ext = F.GCODE_EXTENSIONS[data[0] % 3] if data else ".ngc"
        return Input({f"p{ext}": data[1:]}, {"machine": "siemens-840d"})
    if target == "cl":
        ext = F.CL_EXTENSIONS[data[0] % len(F.CL_EXTENSIONS)] if data else ".cl"
        return Input({f"p{ext}": data[1:]}, {"machine": "siemens-840d"})
    name = {"csv": "t.csv", "shdr": "t.shdr", "machine": "m.toml"}[target]
    return Input({name: data})


def input_bytes(target: str, inp: Input) -> bytes:
    """The inverse of :func:`bytes_input` (corpus seeds for atheris)."""
    (name, data), *_ = inp.files.items()
    if target == "gcode":
        return bytes([F.GCODE_EXTENSIONS.index(Path(name).suffix)]) + data
    if target == "cl":
        return bytes([F.CL_EXTENSIONS.index(Path(name).suffix)]) + data
    return data


def run_input(target: str, inp: Input, folder: Path) -> None:
    """Run one input; raise on a crash or a property violation."""
    if target == "cli":
        assert inp.case is not None
        try:
            P.run_cli_case(inp.case, folder, random.Random(inp.run_seed), P.call_with_streams)
        except P.PropertyViolation as exc:
            raise P.PropertyViolation(f"{inp.case.command}: {exc.kind}", str(exc)) from None
        return
    (name, data), *_ = inp.files.items()
    if target == "machine":
        P.run_machine(data.decode("utf-8", "replace"), folder)
        return
    path = P.write_input(folder, name, data)
    if target in ("csv", "shdr"):
        P.run_trace(path, inp.options.get("units"))
        return
    machine = P.MACHINES[inp.options.get("machine", "siemens-840d")]
    P.run_program(path, machine, inp.options.get("dialect"), inp.options.get("block_delete", False))


# ----------------------------------------------------------------------------- findings
@dataclass
class Finding:
    key: str
    kind: str  # "crash", "property", "warning"
    message: str
    trace: str
    count: int = 1
    where: str = ""  # reproducer folder


def _site(tb: Any) -> str:
    """file:line of the innermost frame in project code (else of the innermost frame)."""
    frames = []
    while tb is not None:  # tb_lineno, not extract_tb: a frame cut by SIGALRM has a line
        frames.append((tb.tb_frame.f_code.co_filename, tb.tb_lineno))
        tb = tb.tb_next
    for filename, line in reversed(frames):
        if filename.startswith(PROJECT):
            return f"{os.path.relpath(filename, ROOT)}:{line}"
    if frames:
        return f"{Path(frames[-1][0]).name}:{frames[-1][1]}"
    return "?"


def _hang_site(exc: Timeout) -> str | None:
    """The innermost project frame on the stack both at the sample and at the Timeout."""
    then = {id(f) for f in exc.sample}
    now = []
    tb = exc.__traceback__
    while tb is not None:
        now.append(tb.tb_frame)
        tb = tb.tb_next
    site = None
    for frame in reversed(now):
        code = frame.f_code
        if code.co_filename.startswith(PROJECT) and id(frame) in then:
            site = (
                f"{os.path.relpath(code.co_filename, ROOT)}:{code.co_firstlineno} {code.co_name}()"
            )
            break
    exc.sample = []
    return site


def _free(exc: BaseException) -> None:
    """Clear the locals of every frame the exception holds, first thing: after a MemoryError
    or a hang they hold the gigabytes (the sites are still read from the frames' code)."""
    chained: BaseException | None = exc
    while chained is not None:
        traceback.clear_frames(chained.__traceback__)
        chained = chained.__cause__ or chained.__context__


def classify(exc: BaseException) -> Finding:
    if isinstance(exc, P.PropertyViolation):
        key, kind = f"property: {exc.kind}", "property"
    elif isinstance(exc, Timeout):
        key, kind = f"Timeout in {_hang_site(exc) or _site(exc.__traceback__)}", "crash"
    else:
        key, kind = f"{type(exc).__name__} at {_site(exc.__traceback__)}", "crash"
    _free(exc)
    msg = f"{type(exc).__name__}: {exc}"[:500]
    return Finding(key, kind, msg, "".join(traceback.format_exception(exc)))


def attempt(target: str, inp: Input, timeout: float) -> tuple[Finding | None, list[Finding]]:
    """Run one input in a fresh folder with the time limit; the finding (or None) and the
    RuntimeWarnings raised in project code."""
    folder = Path(tempfile.mkdtemp(prefix="ncperf-fuzz-"))
    error: BaseException | None = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        arm(timeout)
        try:
            run_input(target, inp, folder)
        except (Timeout, Exception) as exc:  # MemoryError included
            _free(exc)
            error = exc
        finally:
            disarm()
            shutil.rmtree(folder, ignore_errors=True)
    found = classify(error) if error is not None else None
    del error
    warns = []
    for w in caught:
        if issubclass(w.category, RuntimeWarning) and str(w.filename).startswith(PROJECT):
            where = f"{os.path.relpath(w.filename, ROOT)}:{w.lineno}"
            msg = f"RuntimeWarning: {w.message}"
            warns.append(Finding(f"{msg} at {where}", "warning", msg, ""))
    return found, warns


def minimize(target: str, inp: Input, key: str, timeout: float, budget: float) -> Input:
    """Fewer lines, then fewer bytes per line, while the same finding reproduces (single-file
    targets; at most ``budget`` seconds)."""
    if target == "cli":
        return inp
    (name, data), *_ = inp.files.items()
    end = time.monotonic() + budget

    if key.startswith("Timeout"):
        timeout = min(timeout, 2)  # a hang hangs in 2 s too; the minimizer can try more

    def same(candidate: bytes) -> bool:
        if time.monotonic() > end:
            return False
        f, _ = attempt(target, Input({name: candidate}, inp.options), timeout)
        return f is not None and f.key == key

    lines = data.split(b"\n")
    chunk = max(1, len(lines) // 2)
    while chunk >= 1 and time.monotonic() < end:
        k, changed = 0, False
        while k < len(lines) and time.monotonic() < end:
            trial = lines[:k] + lines[k + chunk :]
            if trial and same(b"\n".join(trial)):
                lines, changed = trial, True
            else:
                k += chunk
        if not changed:
            chunk //= 2
    for i in range(len(lines)):  # shorten each remaining line from the end
        while len(lines[i]) > 1 and time.monotonic() < end:
            cut = lines[:i] + [lines[i][: len(lines[i]) // 2]] + lines[i + 1 :]
            if same(b"\n".join(cut)):
                lines = cut
            else:
                break
    return Input({name: b"\n".join(lines)}, inp.options)


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text)[:80].strip("_")


def save(
    finding: Finding, target: str, inp: Input, minimal: Input | None, out: Path, replay: str
) -> str:
    """Write the reproducer folder of a new finding; its path."""
    digest = hashlib.sha1(finding.key.encode()).hexdigest()[:8]
    folder = out / target / f"{_slug(finding.key)}-{digest}"
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in inp.files.items():
        (folder / _slug(name)).write_bytes(data)
    if minimal is not None:
        for name, data in minimal.files.items():
            (folder / f"min-{_slug(name)}").write_bytes(data)
    info = {"key": finding.key, "message": finding.message, "options": inp.options}
    if inp.case is not None:
        info["case"] = {
            "command": inp.case.command,
            "programs": [n for n, _ in inp.case.programs],
            "machine": inp.case.machine,
            "options": inp.case.options,
            "outputs": inp.case.outputs,
            "trace": inp.case.trace_name if inp.case.trace is not None else "made by profile",
        }
        if inp.case.trace is not None:
            (folder / _slug(inp.case.trace_name)).write_bytes(inp.case.trace)
        if inp.case.machine and "\n" in inp.case.machine:
            (folder / "m.toml").write_text(inp.case.machine, encoding="utf-8")
    (folder / "finding.json").write_text(json.dumps(info, indent=1, default=str) + "\n")
    (folder / "traceback.txt").write_text(finding.trace or finding.message)
    (folder / "replay.txt").write_text(replay + "\n")
    return str(folder)


# ----------------------------------------------------------------------------- engines
@dataclass
class Stats:
    tried: int = 0
    findings: dict[str, Finding] = field(default_factory=dict)
    warnings: dict[str, Finding] = field(default_factory=dict)
    engines: list[str] = field(default_factory=list)


def random_engine(target: str, args: argparse.Namespace, stats: Stats, seconds: float) -> None:
    end = time.monotonic() + seconds
    i = 0
    while time.monotonic() < end:
        inp = make_input(target, random.Random(f"{args.seed}:{target}:{i}"))
        found, warns = attempt(target, inp, args.timeout)
        stats.tried += 1
        for w in warns:
            stats.warnings.setdefault(w.key, w)
        if found is not None:
            if found.key in stats.findings:
                stats.findings[found.key].count += 1
            else:
                minimal = None
                with contextlib.suppress(MemoryError):
                    minimal = minimize(target, inp, found.key, args.timeout, args.minimize)
                replay = f"python benchmarks/fuzz.py --seed {args.seed} --replay {target}:{i}"
                found.where = save(found, target, inp, minimal, args.out, replay)
                stats.findings[found.key] = found
                print(f"  [{target}] new: {found.key}", flush=True)
        i += 1


def _instrument_project() -> int:
    """Atheris coverage for the project's own functions (instrumenting everything loaded
    takes minutes)."""
    import types

    import atheris

    n = 0
    seen: set[int] = set()

    def fn(obj: Any) -> None:
        nonlocal n
        if isinstance(obj, types.FunctionType) and id(obj) not in seen:
            seen.add(id(obj))
            if obj.__code__.co_filename.startswith(PROJECT):
                with contextlib.suppress(Exception):
                    atheris.instrument_func(obj)
                    n += 1

    for name, mod in list(sys.modules.items()):
        if not name.startswith(("core", "adapters", "plugins", "refvm")) or mod is None:
            continue
        for obj in list(vars(mod).values()):
            fn(obj)
            if isinstance(obj, type) and obj.__module__ == name:
                for attr in vars(obj).values():
                    for sub in ("__func__", "fget", "func"):
                        fn(getattr(attr, sub, None))
                    fn(attr)
    return n


def atheris_engine(target: str, args: argparse.Namespace, stats: Stats, seconds: float) -> None:
    """One libFuzzer run in a forked child; findings come back through files."""
    work = args.out / "atheris" / target
    corpus = work / "corpus"
    corpus.mkdir(parents=True, exist_ok=True)
    for i in range(100):  # the generators' inputs as the starting corpus
        inp = make_input(target, random.Random(f"{args.seed}:{target}:corpus:{i}"))
        data = input_bytes(target, inp)
        (corpus / hashlib.sha1(data).hexdigest()).write_bytes(data)
    report, counter = work / "findings.jsonl", work / "tried"
    report.unlink(missing_ok=True)
    counter.write_text("0")
    known = set(stats.findings)
    pid = os.fork()
    if pid == 0:  # child: never returns
        code = 0
        try:
            _atheris_child(target, args, seconds, corpus, report, counter, known, work)
        except BaseException:
            traceback.print_exc()
            code = 1
        os._exit(code)
    deadline = time.monotonic() + seconds + 60
    status = None
    while time.monotonic() < deadline:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        time.sleep(0.5)
    else:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    stats.tried += int(counter.read_text() or 0)
    if report.exists():
        for line in report.read_text().splitlines():
            d = json.loads(line)
            f = Finding(d["key"], d["kind"], d["message"], "", d["count"], d["where"])
            bucket = stats.warnings if f.kind == "warning" else stats.findings
            if f.key in bucket:
                bucket[f.key].count += f.count
            else:
                bucket[f.key] = f
                if f.kind != "warning":
                    print(f"  [{target}/atheris] new: {f.key}", flush=True)
    if status and status != 0:
        print(f"  [{target}/atheris] child ended with status {status}; see {work / 'log.txt'}")


def _atheris_child(
    target: str,
    args: argparse.Namespace,
    seconds: float,
    corpus: Path,
    report: Path,
    counter: Path,
    known: set[str],
    work: Path,
) -> None:
    import atheris

    log = os.open(work / "log.txt", os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    os.dup2(log, 2)  # libFuzzer's progress lines
    n = _instrument_project()
    print(f"instrumented {n} project functions", file=sys.stderr, flush=True)
    signal.signal(signal.SIGALRM, _alarm)
    seen: dict[str, int] = {}
    tried = [0, time.monotonic()]

    def one(data: bytes) -> None:
        tried[0] += 1
        if time.monotonic() - tried[1] > 1:
            counter.write_text(str(tried[0]))
            tried[1] = time.monotonic()
        inp = bytes_input(target, data)
        found, warns = attempt(target, inp, args.timeout)
        for f in ([found] if found else []) + warns:
            if f.key in seen:
                seen[f.key] += 1
                continue
            seen[f.key] = 1
            if f.kind != "warning" and f.key not in known:
                minimal = None
                with contextlib.suppress(MemoryError):
                    minimal = minimize(target, inp, f.key, args.timeout, args.minimize)
                replay = f"the files here ({target}; found by atheris)"
                f.where = save(f, target, inp, minimal, args.out, replay)
            with report.open("a") as fh:
                fh.write(json.dumps(vars(f) | {"trace": ""}) + "\n")

    atheris.Setup(
        [
            sys.argv[0],
            f"-max_total_time={int(seconds)}",
            "-timeout=0",  # the per-input limit is ours (SIGALRM)
            f"-rss_limit_mb={args.memory_gib * 1024}",
            "-max_len=65536",
            "-print_final_stats=0",
            str(corpus),
        ],
        one,
    )
    atheris.Fuzz()


# ----------------------------------------------------------------------------- main
def replay(spec: str, args: argparse.Namespace) -> int:
    target, _, index = spec.partition(":")
    inp = make_input(target, random.Random(f"{args.seed}:{target}:{int(index)}"))
    for name, data in inp.files.items():
        print(f"--- {name} ({len(data)} bytes)\n{data[:4000].decode('utf-8', 'replace')}")
    if inp.case is not None:
        print(f"--- case: {inp.case}")
    folder = Path(tempfile.mkdtemp(prefix="ncperf-replay-"))
    arm(args.timeout)
    run_input(target, inp, folder)  # raises with the full traceback
    disarm()
    print("no finding")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="budget per target (s)")
    ap.add_argument("--out", type=Path, default=Path("/tmp/ncperf-fuzz"), help="reproducers")
    ap.add_argument("--targets", default=",".join(TARGETS), help=",".join(TARGETS))
    ap.add_argument("--engine", choices=("both", "random", "atheris"), default="both")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--timeout", type=float, default=10, help="per input (s)")
    ap.add_argument("--memory-gib", type=int, default=4, help="address-space cap (GiB)")
    ap.add_argument("--minimize", type=float, default=10.0, help="s to minimize a finding")
    ap.add_argument("--replay", metavar="TARGET:INDEX", help="rerun one input of a random run")
    args = ap.parse_args(argv)

    cap = args.memory_gib << 30
    _, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY:
        cap = min(cap, hard)
    resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    signal.signal(signal.SIGALRM, _alarm)
    warnings.simplefilter("ignore")
    if args.replay:
        return replay(args.replay, args)

    try:
        import atheris  # noqa: F401

        have_atheris = True
    except ImportError:
        have_atheris = False
    engines = {"both": ["random", "atheris"], "random": ["random"], "atheris": ["atheris"]}
    wanted = engines[args.engine]
    if "atheris" in wanted and not have_atheris:
        print("atheris is not importable (pip install atheris): random engine only")
        wanted = ["random"]
    args.out.mkdir(parents=True, exist_ok=True)
    targets = [t.strip() for t in args.targets.split(",") if t.strip()]
    results: dict[str, Stats] = {}
    for target in targets:
        if target not in TARGETS:
            ap.error(f"unknown target {target!r} (targets: {', '.join(TARGETS)})")
        stats = results[target] = Stats()
        mine = [e for e in wanted if e == "random" or target in FILE_TARGETS]
        share = args.seconds / len(mine)
        print(f"{target}: {' + '.join(f'{e} {share:.0f} s' for e in mine)}", flush=True)
        for engine in mine:
            stats.engines.append(engine)
            t0, n0 = time.monotonic(), stats.tried
            if engine == "random":
                random_engine(target, args, stats, share)
            else:
                atheris_engine(target, args, stats, share)
            rate = (stats.tried - n0) / max(time.monotonic() - t0, 1e-9)
            print(f"  {engine}: {stats.tried - n0} inputs ({rate:.0f}/s)", flush=True)

    print()
    print(f"{'target':<9} {'engines':<16} {'inputs':>8} {'findings':>9} {'warnings':>9}")
    for target, s in results.items():
        print(
            f"{target:<9} {'+'.join(s.engines):<16} {s.tried:>8} {len(s.findings):>9} "
            f"{len(s.warnings):>9}"
        )
    for target, s in results.items():
        for f in s.findings.values():
            print(f"\n[{target}] {f.key}  (x{f.count})\n  {f.message[:300]}\n  -> {f.where}")
        for w in s.warnings.values():
            print(f"\n[{target}] {w.key}  (x{w.count})")
    summary = {
        t: {
            "inputs": s.tried,
            "findings": {
                k: {"count": f.count, "where": f.where, "message": f.message}
                for k, f in s.findings.items()
            },
            "warnings": {k: w.count for k, w in s.warnings.items()},
        }
        for t, s in results.items()
    }
    (args.out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(f"\nsummary: {args.out / 'summary.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
