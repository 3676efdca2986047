#!/usr/bin/python3
"""pymodbus (Debian python3-pymodbus 3.0) as a master of `canalsim serve --lockstep` with
config/sim/plc/asce2.toml: writes the gate setpoint of pool 2 and checks that the gate position
read back moves toward it at the PLC's rate limit (0.005 m/s x 10 s steps = 50 mm per step).

Usage: serve_pymodbus.py PORT.  Exit 0 on success, 1 with a message on the first failure.
Register numbers are 0-based protocol addresses (docs/register-map.md)."""
import struct
import sys

from pymodbus.client import ModbusTcpClient

IR_STEP_COUNT = 6
IR_POOL2_SETTING = 111  # 16-bit block: 100 + 8 * record 1 + field 3, mm
IR_POOL2_SETPOINT = 112
IR_POOL2_SETTING_FLOAT = 322  # float block: 300 + 2 * (8 * 1 + 3), m, word order abcd
HR_STEP = 1
HR_POOL2_GATE = 102  # 16-bit block: 100 + 2 * record 1 + field 0, mm
HR_POOL2_GATE_FLOAT = 304
STEP_MM = 50  # 0.005 m/s x 10 s


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def inputs(client, address, count=1):
    r = client.read_input_registers(address, count, slave=1)
    if r.isError():
        fail("read input %d: %s" % (address, r))
    return r.registers


def holding(client, address, count=1):
    r = client.read_holding_registers(address, count, slave=1)
    if r.isError():
        fail("read holding %d: %s" % (address, r))
    return r.registers


def write(client, address, value):
    r = client.write_register(address, value, slave=1)
    if r.isError():
        fail("write %d: %s" % (address, r))


def as_float(words):
    return struct.unpack(">f", struct.pack(">HH", words[0], words[1]))[0]


def main():
    client = ModbusTcpClient("127.0.0.1", port=int(sys.argv[1]), timeout=10)
    if not client.connect():
        fail("cannot connect")
    start = inputs(client, IR_POOL2_SETTING)[0]
    target = start - 300
    write(client, HR_POOL2_GATE, target)
    if holding(client, HR_POOL2_GATE)[0] != target:
        fail("setpoint did not read back")
    if inputs(client, IR_POOL2_SETPOINT)[0] != target:
        fail("active setpoint is not the one written")
    positions = [start]
    for _ in range(8):
        write(client, HR_STEP, 1)
        positions.append(inputs(client, IR_POOL2_SETTING)[0])
    print("positions_mm " + " ".join(str(p) for p in positions))
    for k, p in enumerate(positions):
        expected = max(start - STEP_MM * k, target)
        # One count of rounding: the start is a rounded steady-state opening.
        if abs(p - expected) > 1:
            fail("step %d: position %d mm, expected %d mm" % (k, p, expected))
    f = as_float(inputs(client, IR_POOL2_SETTING_FLOAT, 2))
    if abs(f - target / 1000.0) > 1e-6:
        fail("float position %.6f m, expected %.3f" % (f, target / 1000.0))
    # A float setpoint (two registers, abcd) moves the gate back up at the same rate.
    words = struct.unpack(">HH", struct.pack(">f", 1.5))
    r = client.write_registers(HR_POOL2_GATE_FLOAT, list(words), slave=1)
    if r.isError():
        fail("write float setpoint: %s" % r)
    if holding(client, HR_POOL2_GATE)[0] != 1500:
        fail("float setpoint not mirrored in the 16-bit register")
    write(client, HR_STEP, 2)
    p = inputs(client, IR_POOL2_SETTING)[0]
    if p != target + 2 * STEP_MM:
        fail("after the float setpoint: %d mm, expected %d" % (p, target + 2 * STEP_MM))
    print("float_setpoint_ok %d" % p)
    client.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
