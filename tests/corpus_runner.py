"""Hostile-input corpus: bad, odd and hostile inputs for every reader and every option.

The cases are data, one YAML file per family in ``tests/corpus/`` (see its README), read
by ``tests/corpus_cases.py``, which also builds a case's files from the valid inputs of
``tests/corpus_inputs.py``. Each case runs as ``python -m umbmark ...`` in a subprocess
under a wall-time limit and a 1 GB address-space limit, and its outcome is classified
(:func:`classify`):

* ``ok-result``: exit 0 (stderr holds only ``umbmark: warning:`` / ``umbmark: wrote``
  lines, ``--json`` output is strict JSON);
* ``clean-error``: exit 2 or 3 with exactly one ``umbmark: error:`` line (warnings
  before it allowed);
* ``traceback``: a Python traceback, exit 1 or 70 (an internal error), or a crash;
* ``hang``: the wall-time limit ran out;
* ``memory``: a ``MemoryError`` / "out of memory" under the 1 GB limit, or killed;
* ``wrong-result``: a case with a known-wrong outcome ended with exit 0 without the
  warning that names its cause, a case that must end "do not apply" did not exit 4, or
  an output check failed (after a refusal too);
* ``unclean``: any other stderr text (click's usage block, numpy warnings, ...);
* ``refused-valid``: a valid input that was refused.

Permission cases need a process that file modes apply to: run as root, each case drops
``CAP_DAC_OVERRIDE`` and ``CAP_DAC_READ_SEARCH`` from its bounding set before it starts
(so root obeys modes like any owner); where that is impossible those cases are skipped
and the summary says so.

Usage::

    python tests/corpus_runner.py               # build, run every case, print the summary
    python tests/corpus_runner.py --list        # the cases
    python tests/corpus_runner.py --filter bag  # only cases whose name contains 'bag'
    python tests/corpus_runner.py --jobs 2 --timeout 60 --keep DIR --json F
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from corpus_cases import Case, Outcome, corpus, digest, run_step
from corpus_inputs import build_base

__all__ = ["Case", "Outcome", "build_base", "classify", "corpus", "run_case", "run_corpus"]

#: Address-space limit of every case [bytes]: the issue's "runs over 1 GB".
MEMORY_LIMIT = 1 << 30
#: Default wall-time limit of a case [s]: longer is a hang.
TIMEOUT = 60.0

FAILURES = ("traceback", "hang", "memory", "wrong-result", "unclean", "refused-valid")
CLASSES = ("ok-result", "clean-error", *FAILURES)


@dataclass
class Verdict:
    """A case's class and, for failures, why."""

    case: Case
    klass: str
    detail: str
    outcome: Outcome
    command: str


def _lines(text: str) -> list[str]:
    return [line for line in text.splitlines() if line.strip()]


def classify(case: Case, out: Outcome, case_dir: Path | None = None) -> tuple[str, str]:
    """The class of an outcome (see the module docstring) and a short reason."""
    text = out.stdout + out.stderr
    err = _lines(out.stderr)
    if out.returncode is None:
        return "hang", f"no end within {out.seconds:.0f} s"
    if "MemoryError" in text or any("out of memory" in line for line in err):
        return "memory", "ran out of the 1 GB address space"
    if out.returncode in (-signal.SIGKILL, 137):
        return "memory", "killed"
    if "Traceback" in text:
        return "traceback", "a Python traceback"
    if out.returncode == 70 or any("internal error" in line for line in err):
        return "traceback", "internal error (exit 70)"
    broken_pipe = case.stdout == "head"
    if out.returncode == 1 and not broken_pipe:
        return "traceback", "exit 1"
    if out.returncode not in (0, 1, 2, 3, 4):  # 4: a result not to apply
        return "traceback", f"exit {out.returncode}"
    # ours: errors, warnings, files written and notes of what was done (``umbmark: ...``)
    stray = [line for line in err if not line.startswith("umbmark: ")]
    if stray:
        return "unclean", f"stderr not ours: {stray[0][:120]}"
    errors = [line for line in err if line.startswith("umbmark: error: ")]
    if out.returncode in (2, 3):
        if len(errors) != 1 or err[-1] != errors[0]:
            return "unclean", f"{len(errors)} error line(s) on exit {out.returncode}"
        if case.expect in ("ok", "do-not-apply"):
            return "refused-valid", errors[0][:160]
        problem = case.check(case_dir, out) if case.check and case_dir is not None else None
        if problem:  # a refusal must leave the files as they were, too
            return "wrong-result", problem
        return "clean-error", errors[0][:160]
    if errors:
        return "unclean", "an error line on exit 0"
    if broken_pipe:
        return "ok-result", "quiet on a broken pipe"
    if "--json" in case.argv and case.stdout == "pipe":
        problem = _strict_json(out.stdout)
        if problem:
            return "wrong-result", f"--json output: {problem}"
    if case.expect == "error":
        return "wrong-result", f"accepted (exit {out.returncode}); it must be refused"
    if case.expect == "do-not-apply" and out.returncode != 4:
        return "wrong-result", f"exit {out.returncode}; a result not to apply exits 4"
    if case.expect == "warn":
        warnings = [line.lower() for line in err if line.startswith("umbmark: warning: ")]
        wanted = [w.lower() for w in case.warn]
        if not any(not wanted or any(w in line for w in wanted) for line in warnings):
            return "wrong-result", f"exit 0 without a warning about {' / '.join(case.warn)}"
    if case.check is not None and case_dir is not None:
        problem = case.check(case_dir, out)
        if problem:
            return "wrong-result", problem
    return "ok-result", "exit 0"


def _strict_json(text: str) -> str | None:
    def refuse(name: str) -> float:
        raise ValueError(f"{name} is not JSON")

    try:
        json.loads(text, parse_constant=refuse)
    except ValueError as exc:
        return str(exc).splitlines()[0][:100]
    return None


# --- running --------------------------------------------------------------------------

#: Runs in the child before umbmark: the 1 GB address-space limit and, for root, the
#: capabilities that let it ignore file modes dropped from the bounding set (so the exec
#: that follows starts without them); then it runs ``python ARGS`` as its own child,
#: writes that child's peak resident memory [KiB] to ``$UMBMARK_CORPUS_RSS`` and ends as
#: the child ended (its exit status, or the same signal). A launcher rather than
#: ``preexec_fn``, which is unsafe with the threads of ``--jobs``.
LAUNCHER = f"""
import ctypes, os, resource, signal, sys
resource.setrlimit(resource.RLIMIT_AS, ({MEMORY_LIMIT}, {MEMORY_LIMIT}))
if os.geteuid() == 0:
    libc = ctypes.CDLL(None, use_errno=True)
    for cap in (1, 2):  # CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH
        libc.prctl(24, cap, 0, 0, 0)  # PR_CAPBSET_DROP
pid = os.fork()
if pid == 0:
    os.execv(sys.executable, [sys.executable, *sys.argv[1:]])
for fd in (0, 1):
    os.close(fd)
_, status, usage = os.wait4(pid, 0)
report = os.environ.get("UMBMARK_CORPUS_RSS")
if report:
    with open(report, "w") as file:
        file.write(str(usage.ru_maxrss))
if os.WIFSIGNALED(status):
    signal.signal(os.WTERMSIG(status), signal.SIG_DFL)
    os.kill(os.getpid(), os.WTERMSIG(status))
os._exit(os.waitstatus_to_exitcode(status))
"""


def limited(*args: str) -> list[str]:
    """The command line that runs ``python ARGS`` under :data:`LAUNCHER`'s limits."""
    return [sys.executable, "-c", LAUNCHER, *args]


def modes_apply(folder: Path) -> bool:
    """Do file modes stop a case's process here (a user, or root without DAC caps)?"""
    probe = folder / "mode-probe"
    probe.write_text("x")
    probe.chmod(0)
    try:
        proc = subprocess.run(
            limited("-c", f"open({str(probe)!r}).read()"), capture_output=True, check=False
        )
        return proc.returncode != 0
    finally:
        probe.chmod(0o600)
        probe.unlink()


def build_case(case: Case, case_dir: Path, base: Path) -> None:
    """Make the case's files in ``case_dir`` from the valid inputs in ``base``."""
    for step in case.setup:
        run_step(step, case_dir, base)


def run_case(case: Case, root: Path, base: Path, timeout: float) -> Verdict:
    """Set up the case's files in its own folder under ``root``, run it, classify it."""
    case_dir = root / "".join(c if c.isalnum() or c in "-_.=" else "_" for c in case.name)
    if case_dir.exists() or case_dir.is_symlink():  # a rerun into a kept corpus
        _restore_modes(case_dir)
        shutil.rmtree(case_dir)
    case_dir.mkdir(parents=True)
    argv = [a.replace("{d}", str(case_dir)).replace("{b}", str(base)) for a in case.argv]
    command = "python -m umbmark " + " ".join(_quote(a) for a in argv)
    try:
        build_case(case, case_dir, base)
    except Exception as exc:  # a broken case, not a finding
        out = Outcome(0, "", "", 0.0)
        return Verdict(case, "setup-failed", f"{type(exc).__name__}: {exc}", out, command)
    before = {  # the files the checks name lie in the case's folder itself
        f.name: digest(f)
        for f in case_dir.iterdir()
        if f.is_file() and not f.is_symlink() and os.access(f, os.R_OK)
    }
    env = {**os.environ, "COLUMNS": "80", "OPENBLAS_NUM_THREADS": "1", **case.env}
    env.pop("UMBMARK_HISTORY", None)
    env.setdefault("UMBMARK_HISTORY", str(case_dir / "history.sqlite3"))
    env.update(case.env)
    rss_file = root / f".{case_dir.name}.rss"
    env["UMBMARK_CORPUS_RSS"] = str(rss_file)
    limit = case.timeout or timeout
    start = time.perf_counter()
    devfull = open("/dev/full", "wb") if case.stdout == "full" else None  # noqa: SIM115
    try:
        proc = subprocess.Popen(
            limited("-m", "umbmark", *argv),
            cwd=case_dir,
            stdin=subprocess.DEVNULL,
            stdout=devfull or subprocess.PIPE,
            stderr=subprocess.PIPE,
            env=env,
            start_new_session=True,
        )
    except OSError as exc:  # an argument longer than the kernel takes: a broken case
        if devfull is not None:
            devfull.close()
        out = Outcome(0, "", "", 0.0)
        return Verdict(case, "setup-failed", f"cannot start: {exc}", out, command)
    try:
        if case.stdout == "head":
            assert proc.stdout is not None
            head = proc.stdout.read(10)
            proc.stdout.close()
            _, err = proc.communicate(timeout=limit)
            stdout = head
        else:
            stdout, err = proc.communicate(timeout=limit)
        code: int | None = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        stdout, err = b"", b""
        proc.wait()
        code = None
    finally:
        if devfull is not None:
            devfull.close()
    seconds = time.perf_counter() - start
    peak: float | None = None
    if rss_file.exists():
        text = rss_file.read_text().strip()
        peak = int(text) / 1024 if text.isdigit() else None
        rss_file.unlink()
    decoded = [(s or b"").decode("utf-8", "replace") for s in (stdout, err)]
    out = Outcome(code, *decoded, seconds, peak, before)
    klass, detail = classify(case, out, case_dir)
    _restore_modes(case_dir)
    return Verdict(case, klass, detail, out, command)


def _restore_modes(folder: Path) -> None:
    for path in [folder, *folder.rglob("*")] if folder.exists() else []:
        try:
            if not path.is_symlink():
                path.chmod(0o700 if path.is_dir() else 0o600)
        except OSError:
            pass


def _quote(arg: str) -> str:
    if len(arg) > 120:
        return f"'{arg[:40]}...({len(arg)} chars)'"
    if not arg or any(c in arg for c in " '\"$;|&<>*?()\\\t\n"):
        return "'" + arg.replace("'", "'\\''") + "'"
    return arg


# --- main -----------------------------------------------------------------------------


def summarize(verdicts: Sequence[Verdict], skipped: Sequence[Case], note: str) -> str:
    """The summary table (counts per class, per reader) and the failing cases."""
    readers = sorted({v.case.reader for v in verdicts})
    counts: dict[str, Counter[str]] = defaultdict(Counter)
    for v in verdicts:
        counts[v.case.reader][v.klass] += 1
    shown = [c for c in (*CLASSES, "setup-failed") if any(counts[r][c] for r in readers)]
    width = max([10, *(len(c) for c in shown)])
    lines = [f"{'reader':<10} {'cases':>6} " + " ".join(f"{c:>{width}}" for c in shown)]
    total: Counter[str] = Counter()
    for r in readers:
        total.update(counts[r])
    for r, row in [*((r, counts[r]) for r in readers), ("total", total)]:
        cells = " ".join(f"{row[c]:>{width}}" for c in shown)
        lines.append(f"{r:<10} {sum(row.values()):>6} {cells}")
    peaks = sorted(
        (v.outcome.peak_mib, v.case.name) for v in verdicts if v.outcome.peak_mib is not None
    )
    if peaks:
        top, name = peaks[-1]
        median = peaks[len(peaks) // 2][0]
        lines.append(
            f"peak resident memory of a case: median {median:.0f} MiB, largest {top:.0f} MiB "
            f"({name}); address space limited to {MEMORY_LIMIT >> 20} MiB"
        )
    if skipped:
        lines.append(f"skipped {len(skipped)} case(s): {note}")
    failing = [v for v in verdicts if v.klass in FAILURES or v.klass == "setup-failed"]
    if failing:
        lines += ["", f"{len(failing)} failing case(s):"]
    for v in failing:
        lines.append(f"- [{v.klass}] {v.case.name} ({v.case.reader}): {v.detail}")
        lines.append(f"    $ {v.command}" + _redirect(v.case))
        lines += [f"    ! {line[:200]}" for line in _lines(v.outcome.stderr)[-4:]]
    return "\n".join(lines)


def _redirect(case: Case) -> str:
    env = " ".join(f"{k}={v}" for k, v in case.env.items())
    out = {"full": " > /dev/full", "head": " | head -c 10"}.get(case.stdout, "")
    return (f"   (env {env})" if env else "") + out


#: Why permission cases are skipped where file modes do not apply.
SKIP_NOTE = (
    "file modes do not apply to this process (root with CAP_DAC_OVERRIDE that could "
    "not be dropped): permission cases skipped"
)


def run_corpus(
    cases: Sequence[Case], root: Path, *, jobs: int = 1, timeout: float = TIMEOUT
) -> tuple[list[Verdict], list[Case]]:
    """Build the valid inputs in ``root/_base`` (unless there already) and run ``cases``
    in ``root/cases``, ``jobs`` at a time. Returns the verdicts and the skipped cases."""
    root.mkdir(parents=True, exist_ok=True)
    base = root / "_base"
    if not (base / "session.npz").exists():
        print(f"building the valid inputs in {base} ...", file=sys.stderr)
        build_base(base)
    modes = modes_apply(root)
    skipped = [c for c in cases if c.needs_modes and not modes]
    todo = [c for c in cases if c not in skipped]
    print(f"running {len(todo)} case(s) with {jobs} job(s) ...", file=sys.stderr)

    def one(case: Case) -> Verdict:
        try:
            verdict = run_case(case, root / "cases", base, timeout)
        except Exception as exc:  # a fault of this script: report it, go on
            out = Outcome(0, "", "", 0.0)
            verdict = Verdict(case, "setup-failed", f"{type(exc).__name__}: {exc}", out, "")
        mark = "." if verdict.klass in ("ok-result", "clean-error") else "F"
        print(mark, end="", file=sys.stderr, flush=True)
        return verdict

    try:
        with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
            return list(pool.map(one, todo)), skipped
    finally:
        print(file=sys.stderr)


def _record(v: Verdict) -> dict[str, Any]:
    return {
        "name": v.case.name,
        "reader": v.case.reader,
        "class": v.klass,
        "detail": v.detail,
        "command": v.command + _redirect(v.case),
        "returncode": v.outcome.returncode,
        "seconds": round(v.outcome.seconds, 3),
        "peak_mib": v.outcome.peak_mib,
        "stderr": v.outcome.stderr[-2000:],
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=1, help="cases run in parallel (default 1)")
    parser.add_argument("--filter", default="", help="only cases whose name holds this")
    parser.add_argument("--list", action="store_true", help="list the cases and stop")
    parser.add_argument("--timeout", type=float, default=TIMEOUT, help="wall time of a case [s]")
    parser.add_argument("--keep", type=Path, help="build and keep the corpus in this folder")
    parser.add_argument("--json", type=Path, help="also write every verdict to this JSON file")
    args = parser.parse_args(argv)
    cases = [c for c in corpus() if args.filter in c.name]
    if args.list:
        for c in cases:
            command = " ".join(map(_quote, c.argv))
            print(f"{c.name:<55} {c.reader:<9} {c.expect:<5} umbmark {command}")
        print(f"{len(cases)} case(s)")
        return 0
    root = args.keep or Path(tempfile.mkdtemp(prefix="umbmark-corpus-"))
    started = time.perf_counter()
    try:
        verdicts, skipped = run_corpus(cases, root, jobs=args.jobs, timeout=args.timeout)
    finally:
        if args.keep is None:
            _restore_modes(root)
            shutil.rmtree(root, ignore_errors=True)
    print(summarize(verdicts, skipped, SKIP_NOTE))
    print(f"\n{len(verdicts)} case(s) in {time.perf_counter() - started:.0f} s")
    if args.json:
        args.json.write_text(json.dumps([_record(v) for v in verdicts], indent=1))
    return 1 if any(v.klass in FAILURES for v in verdicts) else 0


if __name__ == "__main__":
    sys.exit(main())
