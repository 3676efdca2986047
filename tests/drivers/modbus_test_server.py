"""Independent Modbus TCP server for canalid's poller tests (pymodbus, Debian's python3).

Usage: /usr/bin/python3 modbus_test_server.py PORT
Serves unit ids 0..255 with 0-based addresses (zero_mode):
  holding 0     = 1234                      (u16; level 1.234 m at 1 mm per count)
  holding 1..2  = float32 3.25, high word first
  holding 3..4  = int32 -123456, low word first (word swapped)
  holding 5     = -42 as int16
  input   0..1  = float32 -0.5, high word first
Reads at addresses >= 100 get exception 2 (illegal data address) from pymodbus.
The values are computed here with struct, independently of canalid's decoder.
"""
import logging
import struct
import sys

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                 ModbusSlaveContext)
from pymodbus.server import StartTcpServer


def words(fmt, value):
    data = struct.pack(fmt, value)
    return [int.from_bytes(data[i:i + 2], "big") for i in range(0, len(data), 2)]


def main():
    port = int(sys.argv[1])
    logging.basicConfig(level=logging.CRITICAL)
    holding = [0] * 100
    holding[0] = 1234
    holding[1:3] = words(">f", 3.25)
    high, low = words(">i", -123456)
    holding[3:5] = [low, high]
    holding[5] = words(">h", -42)[0]
    inputs = [0] * 100
    inputs[0:2] = words(">f", -0.5)
    store = ModbusSlaveContext(hr=ModbusSequentialDataBlock(0, holding),
                               ir=ModbusSequentialDataBlock(0, inputs),
                               zero_mode=True)
    context = ModbusServerContext(slaves=store, single=True)
    StartTcpServer(context=context, address=("127.0.0.1", port), allow_reuse_address=True)


if __name__ == "__main__":
    main()
