"""What every benchmark here does at the end: write its rows (dicts with the
same keys) as CSV and say where; and the memory figures the memory
benchmarks read (Linux /proc)."""
import csv
import os


def write_rows(path, rows):
    """Write rows to path (nothing when path is empty or there are no rows)."""
    if not path or not rows:
        return
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"written {os.path.abspath(path)}")


def status_mb(field):
    """A memory line of /proc/self/status (VmRSS, VmHWM, ...) in MB; NaN
    where there is none."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return float("nan")
