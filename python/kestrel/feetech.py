"""kestrel.feetech: the Feetech SCS/STS serial servo protocol, a bus of STS3215 servos over pyserial,
and the SO-101 leader arm read as the follower's joint angles (`kestrel teleop --device so101leader`).

Wire format (half-duplex TTL bus, 1 Mbit/s 8N1 on the SO-101's Waveshare/Feetech USB adapter):

    instruction  FF FF ID LEN INSTR P1 .. Pn CHK     LEN = n + 2
    status       FF FF ID LEN ERROR P1 .. Pn CHK     LEN = n + 2 (ERROR: the servo's fault bits)
    CHK = ~(ID + LEN + INSTR|ERROR + P1 + .. + Pn) & 0xFF

    PING 0x01 (no parameters; status with no parameters)   READ 0x02 (address, count)
    WRITE 0x03 (address, bytes..)                          SYNC_READ 0x82 to the broadcast id 0xFE
    (address, count, id1, id2, ..): each addressed servo answers in turn with its own status packet.

e.g. the READ of the present position (address 56 = 0x38, 2 bytes) of servo 1 is
FF FF 01 04 02 38 02 BE. Multi-byte registers are little-endian. The STS3215's registers (control
table; EEPROM below 40, RAM from 40) are in `STS3215`; present position is 0..4095 over one turn.

This module needs only the standard library and, for a real port, pyserial (`import serial`): the
pure functions (encode/decode, calibration) work without it, and the tests drive it against
kestrel.feetech_sim's simulated bus on a pseudo-terminal.

Calibration (So101Leader): LeRobot's leader-arm calibration file (lerobot's
`calibration/teleoperators/so101_leader/<id>.json`, and LeIsaac's `so101_leader.json`, the same
layout) holds per motor {id, drive_mode, homing_offset, range_min, range_max}. LeRobot writes
homing_offset into the servo's own Homing_Offset register (31) during calibration, so the servo's
present position already has it subtracted; range_min/range_max are present positions (ticks) at the
ends of the joint's travel, recorded by hand. The conversion to the follower's joint angle is
LeRobot's normalisation followed by LeIsaac's mapping onto the follower's USD joint limits:

    t     = clip(ticks, range_min, range_max)
    arm:     n = (t - range_min) / (range_max - range_min) * 200 - 100     (-100..100; drive_mode 1: -n)
             q = (n + 100) / 200 * (hi - lo) + lo                          degrees, (lo, hi) = joint limits
    gripper: n = (t - range_min) / (range_max - range_min) * 100           (0..100; drive_mode 1: 100 - n)
             q = n / 100 * (hi - lo) + lo
    radians = q * pi / 180

with the follower's joint limits in degrees (LeIsaac's SO-101 USD): shoulder_pan (-110, 110),
shoulder_lift (-100, 100), elbow_flex (-100, 90), wrist_flex (-95, 95), wrist_roll (-160, 160),
gripper (-10, 100). A leader whose servos were never given a homing offset (raw ticks) takes
`homing_in_servo=False`: the offset is then subtracted here, modulo one turn, as the servo would.
"""
from __future__ import annotations

import dataclasses
import json
import math
import os
import time
from typing import Iterable, Mapping, Sequence

HEADER = b"\xff\xff"
BROADCAST_ID = 0xFE

PING = 0x01
READ = 0x02
WRITE = 0x03
REG_WRITE = 0x04
ACTION = 0x05
SYNC_READ = 0x82
SYNC_WRITE = 0x83
INSTRUCTIONS = {PING: "PING", READ: "READ", WRITE: "WRITE", REG_WRITE: "REG_WRITE", ACTION: "ACTION",
                SYNC_READ: "SYNC_READ", SYNC_WRITE: "SYNC_WRITE"}

# The status packet's error byte (Feetech's SCServo SDK names).
STATUS_ERRORS = {0x01: "input voltage", 0x02: "angle sensor", 0x04: "overheat", 0x08: "overcurrent",
                 0x20: "overload"}

# STS3215 control table: name -> (address, size in bytes).
STS3215 = {
    "Firmware_Major_Version": (0, 1), "Firmware_Minor_Version": (1, 1), "Model_Number": (3, 2),
    "ID": (5, 1), "Baud_Rate": (6, 1), "Return_Delay_Time": (7, 1), "Response_Status_Level": (8, 1),
    "Min_Position_Limit": (9, 2), "Max_Position_Limit": (11, 2), "Max_Temperature_Limit": (13, 1),
    "Max_Voltage_Limit": (14, 1), "Min_Voltage_Limit": (15, 1), "Max_Torque_Limit": (16, 2),
    "Phase": (18, 1), "Unloading_Condition": (19, 1), "LED_Alarm_Condition": (20, 1),
    "P_Coefficient": (21, 1), "D_Coefficient": (22, 1), "I_Coefficient": (23, 1),
    "Minimum_Startup_Force": (24, 2), "CW_Dead_Zone": (26, 1), "CCW_Dead_Zone": (27, 1),
    "Protection_Current": (28, 2), "Angular_Resolution": (30, 1), "Homing_Offset": (31, 2),
    "Operating_Mode": (33, 1), "Protective_Torque": (34, 1), "Protection_Time": (35, 1),
    "Overload_Torque": (36, 1),
    # RAM
    "Torque_Enable": (40, 1), "Acceleration": (41, 1), "Goal_Position": (42, 2), "Goal_Time": (44, 2),
    "Goal_Velocity": (46, 2), "Torque_Limit": (48, 2), "Lock": (55, 1), "Present_Position": (56, 2),
    "Present_Velocity": (58, 2), "Present_Load": (60, 2), "Present_Voltage": (62, 1),
    "Present_Temperature": (63, 1), "Status": (65, 1), "Moving": (66, 1), "Present_Current": (69, 2),
}
STS3215_MODEL_NUMBER = 777
TICKS_PER_TURN = 4096
PRESENT_POSITION = STS3215["Present_Position"][0]  # 56 = 0x38
TORQUE_ENABLE = STS3215["Torque_Enable"][0]        # 40


class FeetechError(IOError):
    """A failed exchange on a Feetech bus; names the port, the servo id and the problem."""

    def __init__(self, port: str, servo_id: int | None, problem: str):
        self.port, self.servo_id, self.problem = port, servo_id, problem
        who = f"servo {servo_id}" if servo_id is not None else "bus"
        super().__init__(f"{port}: {who}: {problem}")


class FeetechTimeoutError(FeetechError):
    """No (or a truncated) status packet within the bus's timeout."""


class FeetechChecksumError(FeetechError):
    """A status packet whose checksum does not match its bytes."""


class FeetechPacketError(FeetechError):
    """A malformed status packet: bad length, wrong servo id, unexpected parameter count."""


class FeetechServoError(FeetechError):
    """A servo reported a fault in its status packet's error byte."""


def checksum(body: bytes | Sequence[int]) -> int:
    """~(sum of id, length, instruction/error and parameters) & 0xFF."""
    return ~sum(body) & 0xFF


def encode_instruction(servo_id: int, instruction: int, params: bytes | Sequence[int] = b"") -> bytes:
    """An instruction packet: FF FF id len instr params.. chk."""
    params = bytes(params)
    if not 0 <= servo_id <= 0xFE:
        raise ValueError(f"servo id {servo_id} outside 0..254")
    if len(params) > 250:
        raise ValueError(f"{len(params)} parameter bytes: a packet holds at most 250")
    body = bytes((servo_id, len(params) + 2, instruction)) + params
    return HEADER + body + bytes((checksum(body),))


def encode_status(servo_id: int, error: int = 0, params: bytes | Sequence[int] = b"") -> bytes:
    """A status packet (what a servo answers): FF FF id len error params.. chk."""
    return encode_instruction(servo_id, error, params)


@dataclasses.dataclass(frozen=True)
class Packet:
    """A decoded packet: id, instruction (or a status packet's error byte) and parameters."""
    servo_id: int
    code: int
    params: bytes


def decode_packet(data: bytes, port: str = "<bytes>") -> Packet:
    """One whole packet (header to checksum) checked and decoded; FeetechError subclasses on damage."""
    data = bytes(data)
    sid = data[2] if len(data) > 2 else None
    if len(data) < 6 or data[:2] != HEADER:
        raise FeetechPacketError(port, sid, f"not a packet ({data.hex(' ')})")
    length = data[3]
    if length < 2 or len(data) != length + 4:
        raise FeetechPacketError(port, sid, f"length byte {length} does not match the {len(data)}-byte packet ({data.hex(' ')})")
    want = checksum(data[2:-1])
    if data[-1] != want:
        raise FeetechChecksumError(port, sid, f"checksum 0x{data[-1]:02X}, expected 0x{want:02X} ({data.hex(' ')})")
    return Packet(sid, data[4], data[5:-1])


def read_packet_params(addr: int, count: int) -> bytes:
    return bytes((addr, count))


def sync_read_packet(addr: int, count: int, ids: Iterable[int]) -> bytes:
    """SYNC_READ to the broadcast id: FF FF FE len 82 addr count id.. chk."""
    return encode_instruction(BROADCAST_ID, SYNC_READ, bytes((addr, count, *ids)))


def le_bytes(value: int, size: int) -> bytes:
    return int(value).to_bytes(size, "little", signed=False)


def le_value(data: bytes) -> int:
    return int.from_bytes(data, "little", signed=False)


class FeetechBus:
    """Servos on one serial port. `port` is a device path (/dev/ttyACM0, a pty's slave) or an object
    with pyserial's read/write/reset_input_buffer/close (then `name` names it in errors).

        bus = FeetechBus("/dev/ttyACM0")
        bus.ping(1)                      # the model number (777 for an STS3215)
        bus.read_positions([1, 2, 3])    # {1: ticks, 2: ticks, 3: ticks} by SYNC_READ
        bus.write(1, "Torque_Enable", 0)

    timeout: seconds a status packet may take; a silent servo raises FeetechTimeoutError naming it.
    retries: further attempts after a failed exchange (LeRobot's num_retry).
    read_positions uses SYNC_READ; a bus where no servo answers it (SCS firmware) falls back to one READ
    per servo from then on.
    """

    def __init__(self, port, baudrate: int = 1_000_000, timeout: float = 0.05, retries: int = 0,
                 name: str | None = None):
        if isinstance(port, (str, os.PathLike)):
            import serial  # pyserial

            self.name = name or os.fspath(port)
            try:
                self._ser = serial.Serial(os.fspath(port), baudrate=baudrate, timeout=timeout)
            except (serial.SerialException, OSError) as e:
                raise FeetechError(self.name, None, f"cannot open the port at {baudrate} baud: {e}") from e
        else:
            self._ser = port
            self.name = name or str(getattr(port, "port", None) or port)
        self.timeout = timeout
        self.retries = retries
        self.sync_read_supported: bool | None = None  # None: not tried yet

    # -- context management
    def close(self) -> None:
        if self._ser is not None:
            self._ser.close()
            self._ser = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- raw exchanges
    def _send(self, packet: bytes) -> None:
        if self._ser is None:
            raise FeetechError(self.name, None, "the bus is closed")
        self._ser.reset_input_buffer()  # a stale reply must not pass for this one's
        self._ser.write(packet)
        if hasattr(self._ser, "flush"):
            self._ser.flush()

    def _read_exact(self, n: int, servo_id: int, deadline: float, what: str) -> bytes:
        buf = bytearray()
        while len(buf) < n:
            if time.monotonic() > deadline:
                break
            chunk = self._ser.read(n - len(buf))
            if chunk:
                buf += chunk
        if len(buf) < n:
            got = f"{len(buf)} of {n} bytes" if buf else "no reply"
            raise FeetechTimeoutError(self.name, servo_id, f"{what}: {got} within {self.timeout * 1e3:.0f} ms")
        return bytes(buf)

    def _receive(self, servo_id: int, n_params: int | None, what: str, later: Sequence[int] = ()) -> Packet:
        """One status packet from servo_id: header found (stray bytes skipped), length, checksum, id
        and error byte checked; n_params: the parameter count expected (None: any); later: the ids
        whose replies follow this one's (SYNC_READ), so that one of them arriving names this one silent."""
        deadline = time.monotonic() + self.timeout
        skipped = 0
        prev = None
        while True:  # sync on FF FF
            b = self._read_exact(1, servo_id, deadline, what)
            if prev == 0xFF and b[0] == 0xFF:
                break
            if prev is not None:
                skipped += 1
                if skipped > 64:
                    raise FeetechPacketError(self.name, servo_id, f"{what}: no packet header in 64 bytes")
            prev = b[0]
        # a third FF is the id 0xFF which no servo has: treat as padding (the SDK does the same)
        head = self._read_exact(2, servo_id, deadline, what)
        while head[0] == 0xFF:
            head = head[1:] + self._read_exact(1, servo_id, deadline, what)
        length = head[1]
        if length < 2:
            raise FeetechPacketError(self.name, servo_id, f"{what}: status length byte {length} (at least 2)")
        rest = self._read_exact(length, servo_id, deadline, what)
        pkt = decode_packet(HEADER + head + rest, self.name)  # checksum (names the replying id)
        if pkt.servo_id != servo_id:
            if pkt.servo_id in later:  # SYNC_READ: the next servo's slot came, this one stayed silent
                raise FeetechTimeoutError(self.name, servo_id, f"{what}: no reply (servo {pkt.servo_id} answered in its place)")
            raise FeetechPacketError(self.name, servo_id, f"{what}: the reply came from id {pkt.servo_id}")
        if n_params is not None and len(pkt.params) != n_params:
            raise FeetechPacketError(self.name, servo_id,
                                     f"{what}: {len(pkt.params)} parameter bytes in the reply, expected {n_params}")
        if pkt.code:
            faults = ", ".join(v for k, v in STATUS_ERRORS.items() if pkt.code & k) or f"0x{pkt.code:02X}"
            raise FeetechServoError(self.name, servo_id, f"{what}: the servo reports {faults} (error byte 0x{pkt.code:02X})")
        return pkt

    def _with_retries(self, fn):
        for attempt in range(self.retries + 1):
            try:
                return fn()
            except FeetechError:
                if attempt == self.retries:
                    raise

    # -- instructions
    def ping(self, servo_id: int) -> int:
        """PING servo_id, then read its model number (777: STS3215)."""
        def go():
            self._send(encode_instruction(servo_id, PING))
            self._receive(servo_id, 0, "PING")
            return self.read(servo_id, "Model_Number")
        return self._with_retries(go)

    def read_bytes(self, servo_id: int, addr: int, count: int) -> bytes:
        def go():
            self._send(encode_instruction(servo_id, READ, (addr, count)))
            return self._receive(servo_id, count, f"READ {count} bytes at {addr}").params
        return self._with_retries(go)

    def read(self, servo_id: int, register: str) -> int:
        addr, size = STS3215[register]
        return le_value(self.read_bytes(servo_id, addr, size))

    def write(self, servo_id: int, register: str, value: int) -> None:
        """WRITE a register (a status reply is awaited unless servo_id is the broadcast id)."""
        addr, size = STS3215[register]
        def go():
            self._send(encode_instruction(servo_id, WRITE, bytes((addr,)) + le_bytes(value, size)))
            if servo_id != BROADCAST_ID:
                self._receive(servo_id, 0, f"WRITE {register}")
        self._with_retries(go)

    def sync_read_bytes(self, ids: Sequence[int], addr: int, count: int) -> dict[int, bytes]:
        """SYNC_READ count bytes at addr from every id (replies in the order of ids)."""
        ids = list(ids)
        def go():
            self._send(sync_read_packet(addr, count, ids))
            return {i: self._receive(i, count, f"SYNC_READ {count} bytes at {addr}", later=ids[k + 1:]).params
                    for k, i in enumerate(ids)}
        return self._with_retries(go)

    def read_positions(self, ids: Sequence[int]) -> dict[int, int]:
        """Present position (ticks, 0..4095) of each servo: SYNC_READ, or READ one by one on a bus
        that never answered SYNC_READ."""
        ids = list(ids)
        addr, size = STS3215["Present_Position"]
        if self.sync_read_supported is not False:
            try:
                out = self.sync_read_bytes(ids, addr, size)
                self.sync_read_supported = True
                return {i: le_value(b) for i, b in out.items()}
            except FeetechTimeoutError as e:
                # Only when not even the first servo answered, and SYNC_READ never worked here, is
                # it taken for a bus without SYNC_READ; otherwise the silent servo is the error.
                if self.sync_read_supported or e.servo_id != ids[0] or "no reply" not in e.problem:
                    raise
                self.sync_read_supported = False
        return {i: le_value(self.read_bytes(i, addr, size)) for i in ids}

    def set_torque(self, ids: Iterable[int], enabled: bool) -> None:
        for i in ids:
            self.write(i, "Torque_Enable", int(bool(enabled)))


# -- the SO-101 leader arm -------------------------------------------------------------------------

SO101_JOINTS = ("shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper")
# The follower's joint limits in degrees (LeIsaac's SO-101 USD), onto which the leader's normalised
# range is mapped.
SO101_FOLLOWER_JOINT_LIMITS_DEG = {
    "shoulder_pan": (-110.0, 110.0), "shoulder_lift": (-100.0, 100.0), "elbow_flex": (-100.0, 90.0),
    "wrist_flex": (-95.0, 95.0), "wrist_roll": (-160.0, 160.0), "gripper": (-10.0, 100.0),
}


@dataclasses.dataclass
class JointCalibration:
    """One motor of LeRobot's calibration file: servo id, drive_mode (1: reversed), homing_offset
    (ticks; the servo subtracts it), range_min/range_max (present-position ticks at the ends of travel)."""
    id: int
    drive_mode: int = 0
    homing_offset: int = 0
    range_min: int = 0
    range_max: int = TICKS_PER_TURN - 1

    def __post_init__(self):
        if self.range_max <= self.range_min:
            raise ValueError(f"servo {self.id}: range_max {self.range_max} must exceed range_min {self.range_min}")


def default_calibration() -> dict[str, JointCalibration]:
    """Ids 1..6, the full turn as the range, no offsets (tests and a first look; calibrate a real arm)."""
    return {name: JointCalibration(id=i + 1) for i, name in enumerate(SO101_JOINTS)}


def load_calibration(path: str | os.PathLike) -> dict[str, JointCalibration]:
    """LeRobot's (and LeIsaac's) so101_leader calibration JSON: {motor: {id, drive_mode,
    homing_offset, range_min, range_max}} for the six motors."""
    with open(path) as f:
        data = json.load(f)
    missing = [j for j in SO101_JOINTS if j not in data]
    if missing:
        raise ValueError(f"{os.fspath(path)}: no calibration for {', '.join(missing)}")
    out = {}
    for j in SO101_JOINTS:
        m = data[j]
        try:
            out[j] = JointCalibration(id=int(m["id"]), drive_mode=int(m.get("drive_mode", 0)),
                                      homing_offset=int(m.get("homing_offset", 0)),
                                      range_min=int(m["range_min"]), range_max=int(m["range_max"]))
        except (KeyError, ValueError, TypeError) as e:
            raise ValueError(f"{os.fspath(path)}: motor {j!r}: {e}") from e
    return out


def save_calibration(calibration: Mapping[str, JointCalibration], path: str | os.PathLike) -> None:
    with open(path, "w") as f:
        json.dump({j: dataclasses.asdict(c) for j, c in calibration.items()}, f, indent=4)


def ticks_to_radians(joint: str, ticks: int, cal: JointCalibration, homing_in_servo: bool = True) -> float:
    """The follower's joint angle (rad) for the leader's present position (see the module docstring)."""
    t = int(ticks)
    if not homing_in_servo:
        t = (t - cal.homing_offset) % TICKS_PER_TURN
    t = min(max(t, cal.range_min), cal.range_max)
    frac = (t - cal.range_min) / (cal.range_max - cal.range_min)  # 0..1
    if cal.drive_mode:
        frac = 1.0 - frac  # -n on -100..100 and 100-n on 0..100 are both this
    lo, hi = SO101_FOLLOWER_JOINT_LIMITS_DEG[joint]
    return math.radians(lo + frac * (hi - lo))


def radians_to_ticks(joint: str, radians: float, cal: JointCalibration) -> int:
    """The inverse of ticks_to_radians (homing in the servo), rounded to a tick (tests, the simulator)."""
    lo, hi = SO101_FOLLOWER_JOINT_LIMITS_DEG[joint]
    frac = (math.degrees(radians) - lo) / (hi - lo)
    if cal.drive_mode:
        frac = 1.0 - frac
    return int(round(cal.range_min + frac * (cal.range_max - cal.range_min)))


class So101Leader:
    """The SO-101 leader arm as a teleoperation device: `joint_targets()` is the follower's 6 absolute
    joint targets (rad: shoulder_pan, shoulder_lift, elbow_flex, wrist_flex, wrist_roll, gripper),
    the action of the task env's joint mode.

        leader = So101Leader("/dev/ttyACM0", "so101_leader.json")   # or calibration=dict / None
        q = leader.joint_targets()

    On connect the servos' torque is switched off (the arm is moved by hand), as LeRobot and LeIsaac do.
    """

    mode = "joint"

    def __init__(self, port, calibration: str | os.PathLike | Mapping[str, JointCalibration] | None = None,
                 baudrate: int = 1_000_000, timeout: float = 0.05, homing_in_servo: bool = True,
                 disable_torque: bool = True, bus: FeetechBus | None = None):
        if calibration is None:
            calibration = default_calibration()
        elif not isinstance(calibration, Mapping):
            calibration = load_calibration(calibration)
        self.calibration = dict(calibration)
        self.homing_in_servo = homing_in_servo
        self.bus = bus or FeetechBus(port, baudrate=baudrate, timeout=timeout)
        self.ids = [self.calibration[j].id for j in SO101_JOINTS]
        if disable_torque:
            self.bus.set_torque(self.ids, False)

    def read_ticks(self) -> dict[str, int]:
        pos = self.bus.read_positions(self.ids)
        return {j: pos[self.calibration[j].id] for j in SO101_JOINTS}

    def joint_targets(self) -> list[float]:
        ticks = self.read_ticks()
        return [ticks_to_radians(j, ticks[j], self.calibration[j], self.homing_in_servo) for j in SO101_JOINTS]

    def action(self, observation=None) -> list[float]:
        return self.joint_targets()

    def close(self) -> None:
        self.bus.close()
