"""What the Python throughput benches share: the CPU's name for their rows, and writing the rows
as a CSV (bench/results/python/). Imported by the scripts beside it (run as files, so this folder
is on sys.path)."""
import csv
import os
import platform


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def write_rows(path, rows):
    """rows: dicts with the same keys, written in their order; prints where."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    print("wrote", os.path.abspath(path))
