"""Mutation check of the rule modules: do the tests pin the rules, or only run them?

cosmic-ray (the ``mutation`` extra: ``pip install -e '.[mutation]'``) changes one operator,
number or condition of a rule module at a time and runs the tests that concern that module; a
mutant the tests still pass on ("survived") is a way to bend the rule that no test notices.
Survivors judged equivalent (the mutant cannot change any behaviour) are listed, each with its
reason, in ``benchmarks/mutation_equivalent.toml``; the kill rate is taken over the others.

    .venv/bin/python benchmarks/mutation_check.py                 # every module (~15 min on 2 shared cores)
    .venv/bin/python benchmarks/mutation_check.py --module retry  # modules whose path contains "retry"
    .venv/bin/python benchmarks/mutation_check.py --recheck       # only the last survivors, after new tests
    .venv/bin/python benchmarks/mutation_check.py --report-only   # re-read the last sessions

It MUTATES FILES IN PLACE (cosmic-ray's way: the editable install and the ``plugins/`` ->
``povagent_plugins`` folder mapping keep working). Run it only in a checkout you do not edit
meanwhile (a spare git worktree); each file is put back after each mutant, and this script
restores every rule module from its own snapshot on exit, also on Ctrl-C. Not part of CI or of
the pytest suite. Exit status 1 when the overall kill rate is below ``--goal`` (90%).
Modules run one after another: their tests import one another's modules, so two sessions in
one tree at once could let one module's mutant fail another module's tests.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EQUIVALENT_FILE = ROOT / "benchmarks" / "mutation_equivalent.toml"
PYTEST_OPTIONS = ["-x", "-q", "-p", "no:randomly", "-p", "no:cacheprovider", "--no-header", "-W", "ignore::pytest.PytestAssertRewriteWarning"]


@dataclass(frozen=True)
class RuleModule:
    """One rule module, the tests that pin it, and which of its functions hold the rules.

    ``scope`` names the functions/classes whose mutants count (``None``: the whole module; a
    module-level line counts as the name ``"<module>"``). What is left out is plumbing that
    other tests cover (SQLite connections, the group-commit thread, dataset loading).
    """

    path: str
    tests: tuple[str, ...]
    scope: tuple[str, ...] | None = None
    note: str = ""


RULE_MODULES: tuple[RuleModule, ...] = (
    RuleModule("povagent/scoring/normalized_l2.py", ("tests/scoring/test_official_rules.py", "tests/scoring/test_official.py")),
    RuleModule("plugins/scorers/official_scorer.py", ("tests/scoring/test_official_rules.py", "tests/scoring/test_official.py")),
    RuleModule(
        "povagent/geometry/ground_truth.py",
        (
            "tests/geometry/test_ground_truth_rules.py",
            "tests/geometry/test_ground_truth.py",
            "tests/geometry/test_boundary_points.py",
            "tests/geometry/test_counterfactual_rules.py",
        ),
    ),
    RuleModule(
        "povagent/geometry/camera.py",
        ("tests/geometry/test_camera_rules.py", "tests/geometry/test_camera.py"),
        scope=("<module>", "Projection", "Camera", "from_pose", "focal_px", "axes", "to_camera", "project", "project_point", "project_pixels"),
        note="projection only; back-projection (ray, point_at_depth, point_on_plane) serves the generator and agent",
    ),
    RuleModule("povagent/geometry/letterbox.py", ("tests/geometry/test_letterbox_rules.py", "tests/geometry/test_letterbox.py")),
    RuleModule(
        "plugins/parsers/json_answer.py", ("tests/parsers/test_json_choice_rules.py", "tests/parsers/test_corpus.py", "tests/parsers/test_registration.py")
    ),
    RuleModule(
        "plugins/parsers/rescale.py", ("tests/parsers/test_rescale_rules.py", "tests/parsers/test_corpus.py", "tests/parsers/test_json_choice_rules.py")
    ),
    RuleModule("povagent/engine/retry.py", ("tests/engine/test_retry_rules.py", "tests/engine/test_retry.py")),
    RuleModule("povagent/config/retry_policy.py", ("tests/engine/test_retry_rules.py", "tests/engine/test_retry.py")),
    RuleModule(
        "povagent/run/pending.py",
        ("tests/run/test_resume_rules.py",),
        scope=("<module>", "select_instances", "house_major", "KeyPlan", "n_total", "plan_keys", "pending_keys"),
        note="key planning; dataset loading (prepare_dataset, ensure_dataset) left out",
    ),
    RuleModule(
        "povagent/run/journal.py",
        ("tests/run/test_resume_rules.py",),
        scope=("drop_rows",),
        note="drop_rows (re-attempting failed keys); the group-commit writer is exercised by tests/run",
    ),
    RuleModule("povagent/results/rows.py", ("tests/results/test_results_file_rules.py", "tests/results/test_torn_journal.py")),
    RuleModule(
        "povagent/engine/cache.py",
        ("tests/engine/test_cache_key_rules.py", "tests/engine/test_cache.py"),
        scope=("<module>", "identity_json", "cache_key"),
        note="the cache key; the SQLite store is covered by tests/engine/test_cache.py",
    ),
)

#: Operators left out, each for a reason (cosmic-ray's names; regular expressions).
EXCLUDED_OPERATORS = (
    # Each arithmetic operator is replaced by its inverse only (+ <-> -, * <-> /, // -> /), as
    # mutmut does: a test that pins an expression kills that mutant, and cosmic-ray's other ten
    # replacements of the same operator (a shift or bitwise operator on a float, a power) mostly
    # raise TypeError on the first run of the line, which measures coverage, not pinning, and
    # would triple the run time.
    r"core/ReplaceBinaryOperator_(?!Add_Sub$|Sub_Add$|Mul_Div$|Div_Mul$|FloorDiv_Div$)\w+$",
    r"core/ReplaceUnaryOperator_\w+_Invert$",
    # ``is``/``is not`` against ``==``/``<``: on None and singletons they are the same test
    # (equivalent) or a TypeError; the meaningful flip ``is`` <-> ``is not`` is kept.
    r"core/ReplaceComparisonOperator_(Is|IsNot)_(Eq|NotEq|Lt|LtE|Gt|GtE)$",
    r"core/ReplaceComparisonOperator_(Eq|NotEq|Lt|LtE|Gt|GtE)_(Is|IsNot)$",
)


# -- sessions ---------------------------------------------------------------------------------
@dataclass
class Mutant:
    """One mutant's outcome, with the line it changed (``before`` -> ``after``)."""

    operator: str
    occurrence: int
    function: str
    line_no: int
    before: str
    after: str
    outcome: str  # killed | survived | timeout | incompetent
    equivalent_why: str | None = None


@dataclass
class ModuleResult:
    """Counts of one module's session."""

    module: RuleModule
    mutants: list[Mutant] = field(default_factory=list)
    skipped: int = 0
    baseline_s: float = 0.0
    error: str = ""

    def count(self, outcome: str) -> int:
        return sum(1 for m in self.mutants if m.outcome == outcome)

    @property
    def equivalent(self) -> list[Mutant]:
        return [m for m in self.mutants if m.outcome == "survived" and m.equivalent_why]

    @property
    def unexplained(self) -> list[Mutant]:
        return [m for m in self.mutants if m.outcome == "survived" and not m.equivalent_why]

    @property
    def killed(self) -> int:
        """Killed by a failing test or a timeout (an endless loop is a caught change)."""
        return self.count("killed") + self.count("timeout")

    @property
    def non_equivalent(self) -> int:
        """Mutants that ran and are not listed as equivalent (incompetent ones never ran)."""
        return self.killed + len(self.unexplained)


def _session_paths(work_dir: Path, module: RuleModule) -> tuple[Path, Path]:
    stem = module.path.replace("/", "_").removesuffix(".py")
    return work_dir / f"{stem}.toml", work_dir / f"{stem}.sqlite"


def _config(module: RuleModule, test_command: str, timeout: float) -> str:
    return (
        "[cosmic-ray]\n"
        f"module-path = {json.dumps(module.path)}\n"
        f"timeout = {timeout:.1f}\n"
        "excluded-modules = []\n"
        f"test-command = {json.dumps(test_command)}\n\n"
        "[cosmic-ray.distributor]\nname = \"local\"\n"
    )


def annotation_spans(source: str) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    """``((line, col), (end_line, end_col))`` of every type annotation in ``source``.

    Under ``from __future__ import annotations`` an annotation is a string never evaluated,
    so a mutant inside one (``float | None`` -> ``float - None``) cannot change anything.
    """
    import ast

    spans = []
    for node in ast.walk(ast.parse(source)):
        found = []
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            found.append(node.returns)
        elif isinstance(node, (ast.arg, ast.AnnAssign)):
            found.append(node.annotation)
        for a in found:
            if a is not None:
                spans.append(((a.lineno, a.col_offset), (a.end_lineno, a.end_col_offset)))
    return spans


def _skip_out_of_scope(session: Path, module: RuleModule) -> int:
    """Mark as skipped: excluded operators, functions outside the module's scope, annotations."""
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import WorkerOutcome, WorkResult

    excluded = re.compile("|".join(f"(?:{e})" for e in EXCLUDED_OPERATORS))
    source = (ROOT / module.path).read_text(encoding="utf-8")
    postponed = "from __future__ import annotations" in source
    spans = annotation_spans(source) if postponed else []
    skip = []
    with use_db(str(session), WorkDB.Mode.open) as db:
        for item in db.work_items:
            m = item.mutations[0]
            function = m.definition_name or "<module>"
            in_annotation = any(a <= tuple(m.start_pos) < b for a, b in spans)
            if in_annotation or excluded.match(m.operator_name) or (module.scope is not None and function not in module.scope):
                skip.append(item.job_id)
        if skip:
            db.set_multiple_results(skip, WorkResult(output="out of scope", worker_outcome=WorkerOutcome.SKIPPED))
    return len(skip)


def _changed_line(diff: str) -> tuple[int, str, str]:
    """The first changed line of a unified diff: (its line number, before, after), stripped."""
    before = after = ""
    line_no = 0
    old_line = 0
    for line in diff.splitlines():
        hunk = re.match(r"@@ -(\d+)", line)
        if hunk:
            old_line = int(hunk.group(1))
        elif line.startswith(("---", "+++")):
            continue
        elif line.startswith("-"):
            if not before:
                before, line_no = line[1:].strip(), old_line
            old_line += 1
        elif line.startswith("+"):
            after = after or line[1:].strip()
        else:
            old_line += 1
    return line_no, before, after


def read_session(module: RuleModule, session: Path, equivalents: list[dict]) -> ModuleResult:
    """Outcomes of a finished session, survivors matched against the equivalence list."""
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import TestOutcome, WorkerOutcome

    result = ModuleResult(module)
    with use_db(str(session), WorkDB.Mode.open) as db:
        pending = len(db.pending_work_items)
        if pending:
            result.error = f"{pending} mutants not run (interrupted session?)"
        for item, res in db.completed_work_items:
            m = item.mutations[0]
            if res.worker_outcome in (WorkerOutcome.SKIPPED, WorkerOutcome.NO_TEST):
                result.skipped += 1
                continue
            if res.test_outcome == TestOutcome.SURVIVED:
                outcome = "survived"
            elif res.test_outcome == TestOutcome.KILLED:
                outcome = "timeout" if res.output == "timeout" else "killed"
            else:
                outcome = "incompetent"
            line_no, before, after = _changed_line(res.diff or "")
            mutant = Mutant(m.operator_name, m.occurrence, m.definition_name or "<module>", line_no, before, after, outcome)
            if outcome == "survived":
                mutant.equivalent_why = _equivalence(module, mutant, equivalents)
            result.mutants.append(mutant)
    result.mutants.sort(key=lambda x: (x.line_no, x.operator, x.occurrence))
    return result


def load_equivalents(path: Path = EQUIVALENT_FILE) -> list[dict]:
    """The checked-in list of survivors judged equivalent (each with ``why``)."""
    import tomllib

    if not path.exists():
        return []
    entries = tomllib.loads(path.read_text(encoding="utf-8")).get("equivalent", [])
    for i, e in enumerate(entries):
        missing = {"module", "operator", "line", "mutant", "why"} - set(e)
        if missing:
            raise SystemExit(f"{path}: entry {i + 1} lacks {', '.join(sorted(missing))}")
        e["_used"] = False
    return entries


def _equivalence(module: RuleModule, mutant: Mutant, equivalents: list[dict]) -> str | None:
    for e in equivalents:
        same_function = e.get("function", mutant.function) == mutant.function
        if same_function and (e["module"], e["operator"], e["line"], e["mutant"]) == (module.path, mutant.operator, mutant.before, mutant.after):
            e["_used"] = True
            return str(e["why"])
    return None


def _forget_survivors(session: Path) -> int:
    """Drop the results of the session's survivors, so that ``exec`` runs them again."""
    from cosmic_ray.work_db import WorkDB, WorkResultStorage, use_db
    from cosmic_ray.work_item import TestOutcome

    with use_db(str(session), WorkDB.Mode.open) as db:
        survived = [job for job, res in db.results if res.test_outcome == TestOutcome.SURVIVED]
        with db._session_maker.begin() as sql:  # cosmic-ray has no public call for this
            sql.query(WorkResultStorage).filter(WorkResultStorage.job_id.in_(survived)).delete()
    return len(survived)


def run_module(module: RuleModule, work_dir: Path, test_prefix: list[str], timeout: float | None, recheck: bool = False) -> float:
    """Baseline, init, filter and execute one module's session; returns the baseline seconds.

    With ``recheck`` an existing session keeps its results except the survivors, and ``exec``
    runs those and any mutant an interrupted run left pending."""
    cfg_path, session = _session_paths(work_dir, module)
    tests = [t for t in module.tests if (ROOT / t).exists()]
    if not tests:
        raise RuntimeError(f"{module.path}: none of its tests exist ({', '.join(module.tests)})")
    args = [*PYTEST_OPTIONS, *tests]
    # The baseline also writes the .pyc files (bytecode and pytest's rewritten tests) that
    # every mutant's run then reads: cosmic-ray runs tests with PYTHONDONTWRITEBYTECODE=1, so
    # that a mutated module is never cached.
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    t0 = time.monotonic()
    base = subprocess.run([sys.executable, "-m", "pytest", *args], cwd=ROOT, env=env, capture_output=True, text=True)
    baseline_s = time.monotonic() - t0
    if base.returncode != 0:
        raise RuntimeError(f"{module.path}: the tests fail on unmutated code:\n{base.stdout[-3000:]}")
    per_mutant = timeout if timeout is not None else max(30.0, 4 * baseline_s)
    cfg_path.write_text(_config(module, shlex.join([*test_prefix, *args]), per_mutant), encoding="utf-8")
    cr = [sys.executable, "-m", "cosmic_ray.cli"]
    if recheck and session.exists():
        print(f"   rechecking {_forget_survivors(session)} survivors", flush=True)
    else:
        subprocess.run([*cr, "init", "--force", str(cfg_path), str(session)], cwd=ROOT, check=True)
        _skip_out_of_scope(session, module)
    subprocess.run([*cr, "exec", str(cfg_path), str(session)], cwd=ROOT, check=True)
    return baseline_s


# -- report -----------------------------------------------------------------------------------
def print_report(results: list[ModuleResult], equivalents: list[dict], goal: float) -> tuple[bool, dict[str, int], float]:
    """Print the table, the unexplained survivors and stale equivalence entries; ``(goal met,
    totals, overall kill rate)``."""
    head = f"{'module':38} {'mutants':>7} {'killed':>6} {'t/o':>4} {'incomp':>6} {'equiv':>5} {'surv':>4} {'kill rate':>9}"
    print("\n" + head + "\n" + "-" * len(head))
    tot = {"mutants": 0, "killed": 0, "timeout": 0, "incompetent": 0, "equivalent": 0, "survived": 0, "non_eq": 0}
    for r in results:
        if r.error and not r.mutants:
            print(f"{r.module.path:38} ERROR: {r.error.splitlines()[0]}")
            continue
        rate = r.killed / r.non_equivalent if r.non_equivalent else 1.0
        n = len(r.mutants)
        print(f"{r.module.path:38} {n:7d} {r.count('killed'):6d} {r.count('timeout'):4d} {r.count('incompetent'):6d} "
              f"{len(r.equivalent):5d} {len(r.unexplained):4d} {rate:9.1%}" + (f"  ({r.error})" if r.error else ""))
        for key, value in (("mutants", n), ("killed", r.count("killed")), ("timeout", r.count("timeout")),
                           ("incompetent", r.count("incompetent")), ("equivalent", len(r.equivalent)),
                           ("survived", len(r.unexplained)), ("non_eq", r.non_equivalent)):
            tot[key] += value
    overall = (tot["killed"] + tot["timeout"]) / tot["non_eq"] if tot["non_eq"] else 1.0
    print("-" * len(head))
    print(f"{'overall':38} {tot['mutants']:7d} {tot['killed']:6d} {tot['timeout']:4d} {tot['incompetent']:6d} "
          f"{tot['equivalent']:5d} {tot['survived']:4d} {overall:9.1%}")
    print("kill rate = (killed + timeouts) / (mutants run - incompetent - listed equivalent); goal", f"{goal:.0%}")
    for r in results:
        if r.module.note:
            print(f"  scope of {r.module.path}: {r.module.note}")
    survivors = [(r.module.path, m) for r in results for m in r.unexplained]
    if survivors:
        print(f"\n{len(survivors)} survivors neither killed nor listed as equivalent:")
        for path, m in survivors:
            print(f"  {path}:{m.line_no} [{m.function}] {m.operator}\n      - {m.before}\n      + {m.after}")
    stale = [e for e in equivalents if not e["_used"] and any(r.module.path == e["module"] for r in results)]
    if stale:
        print(f"\n{len(stale)} equivalence entries matched no survivor (the line changed, or a test now kills it):")
        for e in stale:
            print(f"  {e['module']} {e['operator']}: {e['line']!r} -> {e['mutant']!r}")
    return overall >= goal, tot, overall


def record_figures(totals: dict[str, int], overall: float) -> None:
    """Write ``benchmarks/results/mutation_check.json`` (a check of every rule module only)."""
    from results_file import figure, record

    record("mutation_check", [
        figure("mutants of the rule modules", totals["mutants"], "mutants"),
        figure("non-equivalent mutants killed", round(100 * overall, 1), "%", ">= 90%",
               f"{totals['equivalent']} listed as equivalent with reasons in benchmarks/mutation_equivalent.toml"),
        figure("survivors neither killed nor listed as equivalent", totals["survived"], "mutants", "0"),
    ], command="pip install -e '.[mutation]' && python benchmarks/mutation_check.py")


def _report(results: list[ModuleResult], equivalents: list[dict], goal: float, every_module: bool) -> int:
    met, totals, overall = print_report(results, equivalents, goal)
    if every_module and not any(r.error for r in results):
        record_figures(totals, overall)
    return 0 if met else 1


def _snapshot(modules: list[RuleModule]) -> dict[Path, bytes]:
    return {ROOT / m.path: (ROOT / m.path).read_bytes() for m in modules}


def _restore(snapshot: dict[Path, bytes]) -> None:
    for path, data in snapshot.items():
        if path.read_bytes() != data:
            path.write_bytes(data)
            print(f"restored {path.relative_to(ROOT)}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Run the mutation check (see the module docstring)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--module", action="append", default=[], help="only modules whose path contains this (repeatable)")
    p.add_argument("--work-dir", type=Path, default=Path("/tmp/povagent-mutation"), help="sessions and configs")
    p.add_argument("--timeout", type=float, default=None, help="seconds per mutant (default: max(30, 4 x baseline))")
    p.add_argument("--report-only", action="store_true", help="print the report of the last sessions")
    p.add_argument("--recheck", action="store_true",
                   help="run only the last sessions' survivors again (after adding tests; killed mutants stay killed)")
    p.add_argument("--goal", type=float, default=0.90)
    args = p.parse_args(argv)

    modules = [m for m in RULE_MODULES if not args.module or any(s in m.path for s in args.module)]
    if not modules:
        p.error(f"no rule module matches {args.module}")
    args.work_dir.mkdir(parents=True, exist_ok=True)
    equivalents = load_equivalents()
    results: list[ModuleResult] = []
    if args.report_only:
        for m in modules:
            session = _session_paths(args.work_dir, m)[1]
            results.append(read_session(m, session, equivalents) if session.exists() else ModuleResult(m, error="no session"))
        return _report(results, equivalents, args.goal, not args.module)

    snapshot = _snapshot(modules)
    previous_term = signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    started = time.monotonic()
    try:
        prefix = [sys.executable, "-m", "pytest"]
        for m in modules:
            print(f"== {m.path}", flush=True)
            t0 = time.monotonic()
            try:
                baseline = run_module(m, args.work_dir, prefix, args.timeout, args.recheck)
            except (RuntimeError, subprocess.CalledProcessError) as exc:
                results.append(ModuleResult(m, error=str(exc)))
                print(exc, file=sys.stderr)
                continue
            finally:
                _restore(snapshot)
            r = read_session(m, _session_paths(args.work_dir, m)[1], equivalents)
            r.baseline_s = baseline
            results.append(r)
            print(f"   {len(r.mutants)} mutants in {time.monotonic() - t0:.0f} s (baseline {baseline:.1f} s)", flush=True)
    finally:
        _restore(snapshot)
        signal.signal(signal.SIGTERM, previous_term)
    print(f"\ntotal time {time.monotonic() - started:.0f} s")
    return _report(results, equivalents, args.goal, not args.module)


if __name__ == "__main__":
    sys.exit(main())
