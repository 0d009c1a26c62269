"""An error path of a command, checked whole (issue 34): the command exits non-zero, its
output (stdout and stderr) matches PATTERN (Python re, '.' across lines), and OUTPUT, the
file or folder it was told to write, was not left behind ('-' when it writes nothing).

    expect_error.py OUTPUT PATTERN -- COMMAND [ARG...]

ctest's PASS_REGULAR_EXPRESSION ignores the exit code: a command that printed the error and
exited 0 would pass it."""
import os
import re
import shutil
import subprocess
import sys


def main() -> int:
    if len(sys.argv) < 5 or sys.argv[3] != "--":
        print(__doc__, file=sys.stderr)
        return 2
    output, pattern, command = sys.argv[1], sys.argv[2], sys.argv[4:]
    if output != "-":
        if os.path.isdir(output) and not os.path.islink(output):
            shutil.rmtree(output)
        elif os.path.lexists(output):
            os.remove(output)
    run = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=600)
    text = run.stdout.decode("utf-8", "replace")
    sys.stdout.write(text)
    failures = []
    if run.returncode == 0:
        failures.append("the command exited 0")
    if run.returncode < 0:
        failures.append(f"the command died of signal {-run.returncode}")
    if not re.search(pattern, text, re.S):
        failures.append(f"its output does not match {pattern!r}")
    if output != "-" and os.path.lexists(output):
        failures.append(f"{output} was left behind")
    for f in failures:
        print(f"expect_error: FAILED: {f}")
    if not failures:
        print(f"expect_error: ok (exit {run.returncode}, message matched, nothing written)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
