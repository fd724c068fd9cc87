"""kestrel.feetech: the Feetech SCS/STS protocol (packets against hand-computed bytes), FeetechBus
against kestrel.feetech_sim's simulated STS3215 bus on a pseudo-terminal (SYNC_READ, READ fallback,
errors naming the port and the servo), and the SO-101 leader's calibration (LeRobot's JSON)."""
import json
import math

import pytest

from kestrel_pure import load

feetech = load("feetech")
approx = pytest.approx


# -- packets ---------------------------------------------------------------------------------------

def test_read_present_position_packet():
    # FF FF id=01 len=04 READ=02 addr=0x38 count=02 chk=~(01+04+02+38+02)=~0x41=0xBE
    assert feetech.encode_instruction(1, feetech.READ, (0x38, 2)) == bytes.fromhex("FF FF 01 04 02 38 02 BE")


def test_ping_write_sync_read_packets():
    assert feetech.encode_instruction(1, feetech.PING) == bytes.fromhex("FF FF 01 02 01 FB")  # ~0x04
    # WRITE Torque_Enable(40 = 0x28) = 0 on servo 3: ~(03+04+03+28+00) = ~0x32 = 0xCD
    assert feetech.encode_instruction(3, feetech.WRITE, (40, 0)) == bytes.fromhex("FF FF 03 04 03 28 00 CD")
    # SYNC_READ 2 bytes at 0x38 from ids 1..6: len = 6 + 4 = 0x0A;
    # ~(FE+0A+82+38+02+01+02+03+04+05+06) = ~0x1D9 -> 0x26
    assert feetech.sync_read_packet(0x38, 2, range(1, 7)) == bytes.fromhex("FF FF FE 0A 82 38 02 01 02 03 04 05 06 26")


def test_decode_status_and_errors():
    # servo 1 answers 2047 = 0x07FF: FF FF 01 04 00 FF 07 chk=~(01+04+00+FF+07)=~0x10B -> 0xF4
    raw = bytes.fromhex("FF FF 01 04 00 FF 07 F4")
    assert feetech.encode_status(1, 0, (0xFF, 0x07)) == raw
    p = feetech.decode_packet(raw)
    assert (p.servo_id, p.code, feetech.le_value(p.params)) == (1, 0, 2047)
    with pytest.raises(feetech.FeetechChecksumError, match="servo 1.*checksum 0xF5, expected 0xF4"):
        feetech.decode_packet(raw[:-1] + b"\xf5", "/dev/ttyX")
    with pytest.raises(feetech.FeetechPacketError, match="length byte 5"):
        feetech.decode_packet(bytes.fromhex("FF FF 01 05 00 FF 07 F4"))


def test_sts3215_registers():
    assert feetech.STS3215["Present_Position"] == (56, 2)
    assert feetech.STS3215["Torque_Enable"] == (40, 1)
    assert feetech.STS3215["Homing_Offset"] == (31, 2)
    assert feetech.STS3215["Goal_Position"] == (42, 2)


# -- the bus on a pseudo-terminal -----------------------------------------------------------------

@pytest.fixture
def sim():
    pytest.importorskip("serial")
    s = load("feetech_sim").SimulatedServoBus(ids=range(1, 7))
    yield s
    s.close()


@pytest.fixture
def bus(sim):
    b = feetech.FeetechBus(sim.port, timeout=0.1)
    yield b
    b.close()


def test_bus_reads_simulated_ticks(sim, bus):
    ticks = {1: 0, 2: 1024, 3: 2047, 4: 3000, 5: 4095, 6: 1500}
    sim.set_all_ticks(ticks)
    assert bus.ping(3) == 777
    assert bus.read_positions(range(1, 7)) == ticks
    assert bus.sync_read_supported is True
    assert sim.received[-1][:2] == (0xFE, feetech.SYNC_READ)
    assert bus.read(5, "Present_Position") == 4095
    bus.write(2, "Torque_Enable", 0)
    assert sim.register(2, "Torque_Enable") == 0


def test_read_fallback_without_sync_read(sim, bus):
    sim.sync_read = False
    sim.set_all_ticks([10, 20, 30, 40, 50, 60])
    assert bus.read_positions(range(1, 7)) == {1: 10, 2: 20, 3: 30, 4: 40, 5: 50, 6: 60}
    assert bus.sync_read_supported is False
    assert [r[1] for r in sim.received[-6:]] == [feetech.READ] * 6


def test_corrupted_checksum_names_port_and_servo(sim, bus):
    sim.corrupt_next(4)
    with pytest.raises(feetech.FeetechChecksumError) as e:
        bus.read_positions(range(1, 7))
    assert e.value.port == sim.port and e.value.servo_id == 4
    assert sim.port in str(e.value) and "servo 4" in str(e.value) and "checksum" in str(e.value)
    assert bus.read_positions(range(1, 7))[4] == 2047  # the next exchange is clean again
    sim.corrupt_next(2)
    retrying = feetech.FeetechBus(sim.port, timeout=0.1, retries=1)
    assert retrying.read(2, "Present_Position") == 2047  # one retry gets through
    retrying.close()


def test_silent_servo_times_out_naming_port_and_servo(sim, bus):
    sim.silent = {5}
    with pytest.raises(feetech.FeetechTimeoutError) as e:
        bus.read_positions(range(1, 7))
    assert e.value.servo_id == 5 and sim.port in str(e.value) and "servo 5" in str(e.value)
    assert "no reply (servo 6 answered in its place)" in str(e.value)
    with pytest.raises(feetech.FeetechTimeoutError, match="servo 5: SYNC_READ 2 bytes at 56: no reply within 100 ms"):
        bus.read_positions([1, 6, 5])  # the last one silent: the timeout
    with pytest.raises(feetech.FeetechTimeoutError, match="servo 5: PING: no reply"):
        bus.ping(5)
    with pytest.raises(feetech.FeetechTimeoutError, match="servo 9"):
        bus.read(9, "Present_Position")  # an id nobody has


def test_missing_port_is_named():
    pytest.importorskip("serial")
    with pytest.raises(feetech.FeetechError, match="/dev/nonexistent-kestrel-port: bus: cannot open"):
        feetech.FeetechBus("/dev/nonexistent-kestrel-port")


# -- calibration -----------------------------------------------------------------------------------

LEROBOT_CAL = {  # the layout of LeRobot's calibration/teleoperators/so101_leader/<id>.json
    "shoulder_pan": {"id": 1, "drive_mode": 0, "homing_offset": -1024, "range_min": 1000, "range_max": 3000},
    "shoulder_lift": {"id": 2, "drive_mode": 0, "homing_offset": 12, "range_min": 800, "range_max": 3200},
    "elbow_flex": {"id": 3, "drive_mode": 1, "homing_offset": 5, "range_min": 900, "range_max": 3100},
    "wrist_flex": {"id": 4, "drive_mode": 0, "homing_offset": 0, "range_min": 850, "range_max": 3250},
    "wrist_roll": {"id": 5, "drive_mode": 0, "homing_offset": 0, "range_min": 0, "range_max": 4095},
    "gripper": {"id": 6, "drive_mode": 0, "homing_offset": 0, "range_min": 2000, "range_max": 3100},
}


def test_calibration_maps_ticks_to_radians(tmp_path):
    p = tmp_path / "so101_leader.json"
    p.write_text(json.dumps(LEROBOT_CAL))
    cal = feetech.load_calibration(p)
    r = feetech.ticks_to_radians
    # shoulder_pan: the middle of 1000..3000 is the middle of (-110, 110) deg: 0; the ends are the limits
    assert r("shoulder_pan", 2000, cal["shoulder_pan"]) == approx(0.0)
    assert r("shoulder_pan", 1000, cal["shoulder_pan"]) == approx(math.radians(-110))
    assert r("shoulder_pan", 3000, cal["shoulder_pan"]) == approx(math.radians(110))
    assert r("shoulder_pan", 500, cal["shoulder_pan"]) == approx(math.radians(-110))  # clipped
    assert r("shoulder_pan", 1500, cal["shoulder_pan"]) == approx(math.radians(-55))
    # elbow_flex is reversed (drive_mode 1): range_min is the upper limit 90 deg
    assert r("elbow_flex", 900, cal["elbow_flex"]) == approx(math.radians(90))
    assert r("elbow_flex", 3100, cal["elbow_flex"]) == approx(math.radians(-100))
    # gripper 0..100 onto (-10, 100) deg: closed at range_min, 45 deg at 50 %
    assert r("gripper", 2000, cal["gripper"]) == approx(math.radians(-10))
    assert r("gripper", 2550, cal["gripper"]) == approx(math.radians(45))
    # raw ticks (no homing offset in the servo): subtracted here, modulo a turn
    assert r("shoulder_pan", 976, cal["shoulder_pan"], homing_in_servo=False) == approx(0.0)  # 976+1024
    for j in feetech.SO101_JOINTS:
        for q in (-0.15, 0.0, 0.4):
            t = feetech.radians_to_ticks(j, q, cal[j])
            assert r(j, t, cal[j]) == approx(q, abs=2 * math.pi / 4096 * 2)
    p2 = tmp_path / "copy.json"
    feetech.save_calibration(cal, p2)
    assert feetech.load_calibration(p2) == cal


def test_calibration_file_errors(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text(json.dumps({k: v for k, v in LEROBOT_CAL.items() if k != "gripper"}))
    with pytest.raises(ValueError, match="no calibration for gripper"):
        feetech.load_calibration(p)
    bad = dict(LEROBOT_CAL, wrist_flex={"id": 4, "range_min": 3000, "range_max": 1000})
    p.write_text(json.dumps(bad))
    with pytest.raises(ValueError, match="wrist_flex.*range_max 1000 must exceed range_min 3000"):
        feetech.load_calibration(p)


def test_leader_reads_joint_targets(sim, tmp_path):
    p = tmp_path / "so101_leader.json"
    p.write_text(json.dumps(LEROBOT_CAL))
    want = [0.1, -0.5, 0.7, 0.2, -1.0, 0.3]
    cal = feetech.load_calibration(p)
    sim.set_all_ticks([feetech.radians_to_ticks(j, q, cal[j]) for j, q in zip(feetech.SO101_JOINTS, want)])
    leader = feetech.So101Leader(sim.port, p, timeout=0.1)
    try:
        assert [sim.register(i, "Torque_Enable") for i in range(1, 7)] == [0] * 6  # moved by hand
        assert leader.joint_targets() == approx(want, abs=0.002)
        assert leader.mode == "joint"
    finally:
        leader.close()
