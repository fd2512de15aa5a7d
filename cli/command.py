"""`blender -b -c hc_smooth INPUT... -o OUTDIR`: smooth scan files, one progress line per file, a summary.

``main(argv)`` is the function registered with bpy.utils.register_cli_command; tests call it directly
with an argument list (the bpy module cannot run `blender -c`), and scripts/hc_smooth_files.py runs it in
a Python without Blender. PLY, OBJ and STL files take the file route (cli/file_route.py: NumPy and SciPy
only); .blend files are opened in Blender (cli/blend.py, loaded only for them).
"""

import contextlib
import os
import signal
import sys
import threading

from .. import core
from ..jobs import points
from . import arguments, batch, files
from .one_file import Console, Outcome, is_blend, plural, point_settings, process

INTERRUPTED = 130  # 128 + SIGINT, as a shell reports a command stopped by Ctrl+C


def main(argv, prog=arguments.PROG):
    """Run the command on ``argv`` (the arguments after `-c hc_smooth`); returns the exit status.

    ``prog`` names the command in usage messages (the bpy route gives its own)."""
    console = Console()
    try:
        plan = arguments.parse(argv, prog=prog)
        settings = point_settings(plan) if plan.points else plan.settings
    except SystemExit as done:  # --help printed; argparse exits
        return done.code or 0
    except arguments.UsageError as error:
        console.say(error, sys.stderr)
        return 2
    except OSError as error:  # an input that cannot be looked at (an unreadable folder): no traceback
        console.say(f"{error.filename}: {error.strerror}" if error.filename else str(error), sys.stderr)
        return 2
    console.verbose = plan.verbose
    with interruptible():
        outcomes = []
        try:
            return run(plan, settings, console, outcomes)
        except batch.BatchError as error:  # before any file ran: nothing written
            console.say(f"hc_smooth: {error}", sys.stderr)
            return 2
        except KeyboardInterrupt:
            return interrupted(plan, outcomes, console)


def run(plan, settings, console, outcomes):
    for note in plan.notes:
        console.say(f"hc_smooth: note: {note}")
    if plan.points:
        message = points.convergence_note(settings)
    else:
        hc = settings.method == "HC" and not settings.keep_sharp_edges  # Theorem 5.2 is about HC's umbrella
        message = core.convergence_message(settings.alpha, settings.beta) if hc else None
    if message:
        console.say(f"hc_smooth: warning: {message}")
    for folder in dict.fromkeys(os.path.dirname(target) for _, target in plan.files):
        for name in files.remove_stale_temporaries(folder) if os.path.isdir(folder) else ():
            console.say(f"hc_smooth: note: removed {os.path.join(folder, name)}, left by an interrupted run")
    total = len(plan.files)

    def report(outcome):
        console.say(f"[{len(outcomes)}/{total}] {progress_line(outcome)}")
        for text in outcome.legends + outcome.notes if not outcome.error else ():
            console.say(f"  {text}")
        for text in outcome.warnings:
            console.say(f"  warning: {text}")
        for line in outcome.blender_lines:
            console.say(f"  blender: {line}")

    here, away = split_batch(plan)
    if away:
        if here:
            console.say("hc_smooth: note: .blend files run here, one at a time (the workers have no Blender)")
        batch.smooth_files(plan, away, done=lambda outcome: (outcomes.append(outcome), report(outcome)), failed=lost)
    for source, target in here:
        outcome = Outcome(source=source, target=target)
        outcomes.append(outcome)
        process(outcome, plan, settings, console)
        report(outcome)
    order = {source: index for index, (source, _) in enumerate(plan.files)}
    console.say(summary_table(sorted(outcomes, key=lambda outcome: order[outcome.source])))
    failed = [outcome for outcome in outcomes if outcome.error]
    if failed:
        console.say(f"hc_smooth: {len(failed)} of {total} files failed", sys.stderr)
        return 1
    return 0


def split_batch(plan):
    """(files this process smooths, files the workers smooth): with --jobs or --scheduler, every PLY, OBJ and
    STL file goes to the workers; .blend files stay here (they need Blender)."""
    if not plan.batch:
        return plan.files, []
    blend = [(source, target) for source, target in plan.files if is_blend(source)]
    return blend, [pair for pair in plan.files if not is_blend(pair[0])]


def lost(source, target, reason):
    """The outcome of a file that no worker could finish (Dask gave up on it: its workers kept dying)."""
    return Outcome(source=source, target=target, error=f"no worker finished it ({reason})", stage="done")


@contextlib.contextmanager
def interruptible():
    """Ctrl+C (SIGINT) raises KeyboardInterrupt while the command runs, whatever Python handler the host
    installed, which comes back afterwards (a handler set from C cannot be put back from Python: Python's
    stays, and the host exits after the command anyway)."""
    previous = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)


def interrupted(plan, outcomes, console):
    """What an interrupt left: the files done, the one it stopped (as it was), the ones not started."""
    done = [outcome for outcome in outcomes if outcome.stage == "done" and not outcome.error]
    current = outcomes[-1] if outcomes and outcomes[-1].stage != "done" else None
    untouched = len(plan.files) - len(outcomes) + (current is not None)
    where = f" while {current.stage} {current.source}" if current else ""
    console.say(
        f"hc_smooth: interrupted{where}: {plural(len(done), 'file')} of {len(plan.files)} smoothed; "
        f"{plural(untouched, 'file')} left as {'it was' if untouched == 1 else 'they were'} "
        "(no partial output written)",
        sys.stderr,
    )
    return INTERRUPTED


def progress_line(outcome):
    if outcome.error:
        return f"{outcome.source}: FAILED: {outcome.error}"
    return (
        f"{outcome.source} -> {outcome.target}: {outcome.size_text()}, {outcome.amount_text()}, "
        f"{outcome.seconds:.2f} s, {outcome.change_text()}"
    )


def summary_table(outcomes):
    header = ("file", "vertices", "smoothing", "time", "change", "result")
    rows = [header]
    for outcome in outcomes:
        if outcome.error:
            rows.append((outcome.source, "-", "-", f"{outcome.seconds:.2f} s", "-", "FAILED: " + outcome.error))
        else:
            rows.append(
                (
                    outcome.source,
                    str(outcome.vertices),
                    outcome.amount_text(),
                    f"{outcome.seconds:.2f} s",
                    outcome.change_text(),
                    outcome.target,
                )
            )
    widths = [max(len(row[i]) for row in rows) for i in range(len(header) - 1)]
    lines = ["  ".join(cell.ljust(width) for cell, width in zip(row, widths)) + "  " + row[-1] for row in rows]
    done = sum(1 for outcome in outcomes if not outcome.error)
    lines.append(f"{done} of {len(outcomes)} files smoothed")
    return "\n".join(lines)
