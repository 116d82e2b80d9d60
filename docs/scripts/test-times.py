#!/usr/bin/env python3
"""The test suite's run time from a `cargo test` log (e.g. `.ci/run`'s): each test
binary's `finished in`, largest first, and their sum (the build not included).

    python3 docs/scripts/test-times.py LOG
"""
import re
import sys


def binary_times(lines):
    """(seconds, binary) for every binary that ran, from its `Running` and
    `finished in` lines."""
    running = None
    for line in lines:
        started = re.search(r"Running (unittests \S+|\S+)", line)
        if started:
            running = started.group(1)
        finished = re.search(r"finished in ([0-9.]+)s", line)
        if finished and running:
            yield float(finished.group(1)), running
            running = None


def main():
    with open(sys.argv[1]) as log:
        times = sorted(binary_times(log), reverse=True)
    for seconds, binary in times:
        print(f"{seconds:8.1f} s  {binary}")
    total = sum(seconds for seconds, _ in times)
    print(f"{total:8.1f} s  in all ({int(total // 60)} min {total % 60:.0f} s)")


if __name__ == "__main__":
    main()
