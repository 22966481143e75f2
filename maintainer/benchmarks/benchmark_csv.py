"""What every benchmark here does at the end: write its rows (dicts with the
same keys) as CSV and say where."""
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
