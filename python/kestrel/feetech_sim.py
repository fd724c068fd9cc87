"""kestrel.feetech_sim: a simulated Feetech STS3215 servo bus on a pseudo-terminal, for testing
kestrel.feetech (and `--device so101leader`) without a leader arm.

    with SimulatedServoBus(ids=range(1, 7)) as sim:     # opens a pty pair, serves the master side
        sim.set_ticks(1, 2047)
        bus = FeetechBus(sim.port)                      # the slave's path, e.g. /dev/pts/7
        bus.read_positions([1])                         # {1: 2047}

Each servo has a 256-byte control table (model number 777, present position settable); the thread
answers PING, READ, WRITE and SYNC_READ with correctly checksummed status packets, and ignores
packets with a bad checksum or addressed to ids it does not have (as real servos do). Faults on
request: `corrupt_next(servo_id)` flips the checksum of that servo's next reply, `silent` (a set of
ids) makes servos not answer, `sync_read=False` makes the bus ignore SYNC_READ (an SCS-like bus).
Standard library only.
"""
from __future__ import annotations

import os
import select
import threading
import tty

from .feetech import (BROADCAST_ID, PING, READ, STS3215, STS3215_MODEL_NUMBER, SYNC_READ, WRITE, checksum,
                      encode_status)


class SimulatedServoBus:
    def __init__(self, ids=range(1, 7), sync_read: bool = True):
        self.ids = list(ids)
        self.tables = {i: bytearray(256) for i in self.ids}
        for i in self.ids:
            self._poke(i, "Model_Number", STS3215_MODEL_NUMBER)
            self._poke(i, "ID", i)
            self._poke(i, "Max_Position_Limit", 4095)
            self._poke(i, "Torque_Enable", 1)
            self._poke(i, "Present_Position", 2047)
        self.sync_read = sync_read
        self.silent: set[int] = set()
        self.received: list[tuple[int, int, bytes]] = []  # (id, instruction, params) of every good packet
        self._corrupt: dict[int, int] = {}
        self._lock = threading.Lock()
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)  # bytes pass through unchanged (pyserial sets raw mode too)
        self.port = os.ttyname(self.slave)
        self._stop_r, self._stop_w = os.pipe()
        self._thread = threading.Thread(target=self._serve, name="feetech-sim", daemon=True)
        self._thread.start()

    # -- the servos' state
    def _poke(self, sid, register, value):
        addr, size = STS3215[register]
        self.tables[sid][addr:addr + size] = int(value).to_bytes(size, "little")

    def set_ticks(self, sid: int, ticks: int) -> None:
        with self._lock:
            self._poke(sid, "Present_Position", int(ticks) % 4096)

    def set_all_ticks(self, ticks) -> None:
        for sid, t in (ticks.items() if hasattr(ticks, "items") else zip(self.ids, ticks)):
            self.set_ticks(sid, t)

    def register(self, sid: int, register: str) -> int:
        addr, size = STS3215[register]
        with self._lock:
            return int.from_bytes(self.tables[sid][addr:addr + size], "little")

    def corrupt_next(self, sid: int, count: int = 1) -> None:
        """The next `count` replies of servo sid go out with a wrong checksum."""
        with self._lock:
            self._corrupt[sid] = self._corrupt.get(sid, 0) + count

    # -- the wire
    def _reply(self, sid, params=b""):
        if sid in self.silent:
            return b""
        pkt = bytearray(encode_status(sid, 0, params))
        with self._lock:
            if self._corrupt.get(sid):
                self._corrupt[sid] -= 1
                pkt[-1] ^= 0x5A
        return bytes(pkt)

    def _handle(self, sid, instr, params) -> bytes:
        self.received.append((sid, instr, bytes(params)))
        if instr == SYNC_READ and sid == BROADCAST_ID:
            if not self.sync_read or len(params) < 3:
                return b""
            addr, count = params[0], params[1]
            out = b""
            for i in params[2:]:
                if i in self.tables:
                    with self._lock:
                        data = bytes(self.tables[i][addr:addr + count])
                    out += self._reply(i, data)
            return out
        if sid not in self.tables:
            return b""
        if instr == PING:
            return self._reply(sid)
        if instr == READ and len(params) == 2:
            addr, count = params
            with self._lock:
                data = bytes(self.tables[sid][addr:addr + count])
            return self._reply(sid, data)
        if instr == WRITE and len(params) >= 1:
            addr = params[0]
            with self._lock:
                self.tables[sid][addr:addr + len(params) - 1] = params[1:]
            return self._reply(sid)
        return b""

    def _serve(self):
        buf = bytearray()
        while True:
            r, _, _ = select.select([self.master, self._stop_r], [], [])
            if self._stop_r in r:
                return
            try:
                chunk = os.read(self.master, 4096)
            except OSError:
                return
            if not chunk:
                return
            buf += chunk
            while True:
                start = buf.find(b"\xff\xff")
                if start < 0:
                    del buf[:max(0, len(buf) - 1)]
                    break
                del buf[:start]
                if len(buf) < 4:
                    break
                length = buf[3]
                if len(buf) < length + 4:
                    break
                pkt, buf = bytes(buf[:length + 4]), buf[length + 4:]
                if length < 2 or pkt[-1] != checksum(pkt[2:-1]):
                    continue  # a servo ignores a damaged instruction
                out = self._handle(pkt[2], pkt[4], pkt[5:-1])
                if out:
                    os.write(self.master, out)

    def close(self) -> None:
        if self._thread.is_alive():
            os.write(self._stop_w, b"x")
            self._thread.join(timeout=2)
        for fd in (self.master, self.slave, self._stop_r, self._stop_w):
            try:
                os.close(fd)
            except OSError:
                pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
