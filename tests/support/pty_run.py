"""Runs a program with its stderr on a pseudo-terminal (standard library only), for the tests of the
progress lines that Kestrel's commands draw only on a terminal (issue 15): `kestrel run`
(tests/sim/cli_progress_test.py), the bench programs (bench/progress_test.py), `kestrel train` and
`kestrel teleop` (python/tests)."""
import fcntl
import os
import pty
import struct
import subprocess
import termios


def run(cmd, tty=True, timeout=600, columns=0, stdout=subprocess.PIPE):
    """(returncode, stdout text, stderr text) of cmd; with tty, stderr is a fresh pseudo-terminal
    `columns` wide (0: the kernel's default of 0 columns, where tqdm draws an empty bar)."""
    if not tty:
        p = subprocess.run(cmd, stdout=stdout, stderr=subprocess.PIPE, text=True, timeout=timeout)
        return p.returncode, p.stdout or "", p.stderr
    master, slave = pty.openpty()
    if columns:
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, columns, 0, 0))
    p = subprocess.Popen(cmd, stdout=stdout, stderr=slave, close_fds=True)
    os.close(slave)
    err = []
    while True:
        try:
            b = os.read(master, 4096)
        except OSError:  # EIO once the child has closed the terminal
            break
        if not b:
            break
        err.append(b)
    os.close(master)
    out = p.stdout.read().decode() if p.stdout is not None else ""
    return p.wait(timeout=timeout), out, b"".join(err).decode(errors="replace")


def value(s):
    """A progress figure ("4.10M", "512k", "12") as a number."""
    return float(s.rstrip("kMG")) * {"k": 1e3, "M": 1e6, "G": 1e9}.get(s[-1], 1)
