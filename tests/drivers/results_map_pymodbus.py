#!/usr/bin/python3
"""pymodbus (Debian python3-pymodbus 3.0) as a SCADA reading canalidd's results register map.

Usage: results_map_pymodbus.py PORT ADDRESS COUNT
Reads COUNT registers from ADDRESS (0-based protocol addresses, docs/results-register-map.md) with
function 3 and again with function 4, then tries to write the first of them (function 6) and with
function 16.  Prints one JSON object: {"holding": [...], "input": [...], "floats": [...] (the
holding words as f32, high word first), "write_exception": code, "write_multiple_exception": code}.
Exit 1 with a message when a read fails or a write is not refused."""
import json
import math
import struct
import sys

from pymodbus.client import ModbusTcpClient


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def main():
    port, address, count = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
    client = ModbusTcpClient("127.0.0.1", port=port, timeout=5)
    if not client.connect():
        fail("cannot connect to 127.0.0.1:%d" % port)
    holding = client.read_holding_registers(address, count, slave=1)
    if holding.isError():
        fail("read holding %d+%d: %s" % (address, count, holding))
    inputs = client.read_input_registers(address, count, slave=1)
    if inputs.isError():
        fail("read input %d+%d: %s" % (address, count, inputs))
    words = holding.registers
    floats = []
    for i in range(0, count - 1, 2):
        value = struct.unpack(">f", struct.pack(">HH", words[i], words[i + 1]))[0]
        floats.append(None if math.isnan(value) else value)
    write = client.write_register(address, 1234, slave=1)
    if not write.isError():
        fail("a write of register %d was accepted" % address)
    write_multiple = client.write_registers(address, [1, 2], slave=1)
    if not write_multiple.isError():
        fail("a write of registers %d+2 was accepted" % address)
    client.close()
    print(json.dumps({"holding": words, "input": inputs.registers, "floats": floats,
                      "write_exception": write.exception_code,
                      "write_multiple_exception": write_multiple.exception_code}))


main()
