"""Minimal Modbus RTU server on a pseudo-terminal, for canalid's RTU adapter tests.

Usage: /usr/bin/python3 modbus_rtu_pty_server.py UNIT_ID
Prints the pty device path on the first line of stdout once it serves (the ready line), then
answers RTU frames for UNIT_ID only (others are ignored, as on a shared bus):
  function 3/4: holding[i] = 3 i, input[i] = 1000 + i for i in 0..99
  function 6/16: write holding registers
  addresses past 99: exception 2 (illegal data address); other functions: exception 1.
Written from the Modbus over serial line spec (CRC-16/MODBUS, low byte first), independently of
libmodbus. Exits when stdin closes or on a signal.
"""
import os
import pty
import select
import struct
import sys
import tty


def crc16(data):
    crc = 0xFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def frame(body):
    return body + struct.pack("<H", crc16(body))


def request_length(buf):
    """Bytes of the request at the start of buf, or None if more are needed."""
    if len(buf) < 2:
        return None
    function = buf[1]
    if function in (3, 4, 6):
        return 8
    if function == 16:
        return 9 + buf[6] if len(buf) >= 7 else None
    return 4  # unknown function: unit, function, CRC


def answer(unit, request, holding, inputs):
    function = request[1]
    def exception(code):
        return frame(bytes([unit, function | 0x80, code]))
    if function in (3, 4):
        address, count = struct.unpack(">HH", request[2:6])
        if count < 1 or count > 125 or address + count > 100:
            return exception(2)
        table = holding if function == 3 else inputs
        values = table[address:address + count]
        return frame(bytes([unit, function, 2 * count]) + struct.pack(">%dH" % count, *values))
    if function == 6:
        address, value = struct.unpack(">HH", request[2:6])
        if address >= 100:
            return exception(2)
        holding[address] = value
        return frame(request[:6])
    if function == 16:
        address, count = struct.unpack(">HH", request[2:6])
        if address + count > 100:
            return exception(2)
        holding[address:address + count] = struct.unpack(">%dH" % count, request[7:7 + 2 * count])
        return frame(request[:6])
    return exception(1)


def main():
    unit = int(sys.argv[1])
    holding = [3 * i for i in range(100)]
    inputs = [1000 + i for i in range(100)]
    master, slave = pty.openpty()
    tty.setraw(master)
    print(os.ttyname(slave), flush=True)
    buf = b""
    while True:
        ready, _, _ = select.select([master, sys.stdin], [], [])
        if sys.stdin in ready and not os.read(sys.stdin.fileno(), 1024):
            return
        if master not in ready:
            continue
        buf += os.read(master, 1024)
        while True:
            n = request_length(buf)
            if n is None or len(buf) < n:
                break
            request, buf = buf[:n], buf[n:]
            if crc16(request[:-2]) != struct.unpack("<H", request[-2:])[0]:
                buf = b""  # lost sync: drop everything, the client will time out and retry
                break
            if request[0] == unit:
                os.write(master, answer(unit, request, holding, inputs))


if __name__ == "__main__":
    main()
