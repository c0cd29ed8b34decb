# SPDX-License-Identifier: MIT OR Apache-2.0
"""PASS/FAIL/SKIP lines for the Blender acceptance scripts, and their closing summary."""

RESULTS = []


def record(name, ok, detail):
    """Prints and keeps one result: `ok` True (PASS), False (FAIL) or None (SKIP)."""
    status = {True: "PASS", False: "FAIL", None: "SKIP"}[ok]
    RESULTS.append((name, status, detail))
    print(f"{status} {name}: {detail}", flush=True)


def check(name, cond, detail):
    """Records `cond` as PASS or FAIL and returns it."""
    record(name, bool(cond), detail)
    return bool(cond)


def summary():
    """Prints "N passed, N failed, N skipped" and returns the exit status (1 when any failed)."""
    counts = {s: sum(1 for r in RESULTS if r[1] == s) for s in ("PASS", "FAIL", "SKIP")}
    print(f"{counts['PASS']} passed, {counts['FAIL']} failed, {counts['SKIP']} skipped")
    return 1 if counts["FAIL"] else 0
