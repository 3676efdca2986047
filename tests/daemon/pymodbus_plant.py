"""A plant behind an independent Modbus TCP slave (pymodbus, Debian's python3), for canalidd.

Usage: /usr/bin/python3 pymodbus_plant.py PORT PARAMS_JSON
The plant advances one sample of PARAMS_JSON["ts"] plant seconds each time a master reads the
input registers holding the level (address 320), so a daemon polling it once per period sees one
sample per poll however busy the machine is.  Written here from the models' definitions, with
numpy, independently of canalid's code.

Register map (0-based, float32 high word first, the map of canalsim's pool record 1):
  holding 0        heartbeat (any value)
  holding 300-301  actuator setpoint (what the daemon writes)
  input   306-307  actuator position (= the setpoint the last sample used)
  input   316-317  inflow (m3/s)      input 318-319 outflow (m3/s)      input 320-321 level (m)

PARAMS_JSON["kind"]:
  "idz": a pool with the IDZ model (Litrico & Fromion 2004) around a steady state, outflow held:
      level = level0 + (1/(A s) + p21) e^{-tau s} (q_in - q0), the inflow held over each sample
      (zero-order hold) and tau = nk ts, so the inflow that arrives at sample k has added no
      volume yet while its front p21 is there:
      level(k) = level0 + x(k - 1) + p21 (q_in(k - nk) - q0),  x(k) = x(k-1) + ts / A (q_in(k - nk) - q0),
      q_in = q0 + gate_gain (setpoint - setpoint0), nk = delay_samples.
  "fractional": level = level0 + K e^{-tau s} / (1 + T s^alpha) (setpoint - setpoint0) in
      continuous time, the setpoint read with sample k held from t_k to t_(k+1) (zero-order hold)
      and tau = delay_samples x ts, simulated by Grunwald-Letnikov with `substeps` steps per sample
      (full memory): sample k integrates over (t_(k-1), t_k], where the delayed input is the
      setpoint of sample k - 1 - delay_samples.
"""
import json
import logging
import struct
import sys

import numpy as np
from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                 ModbusSlaveContext)
from pymodbus.server import StartTcpServer

LEVEL_ADDRESS = 320


def words(value):
    data = struct.pack(">f", value)
    return [int.from_bytes(data[i:i + 2], "big") for i in range(0, 4, 2)]


def setpoint_of(context):
    high, low = context.store["h"].getValues(300, 2)
    return struct.unpack(">f", struct.pack(">HH", high, low))[0]


class IdzPool:
    def __init__(self, p):
        self.p = p
        self.queue = [p["q0"]] * p["delay_samples"]
        self.x = 0.0

    def step(self, setpoint):
        p = self.p
        q_in = p["q0"] + p["gate_gain"] * (setpoint - p["setpoint0"])
        self.queue.append(q_in)
        arriving = self.queue.pop(0)
        level = p["level0"] + self.x + p["p21"] * (arriving - p["q0"])
        self.x += p["ts"] / p["area"] * (arriving - p["q0"])
        return q_in, p["q0"], level


class FractionalFlume:
    def __init__(self, p):
        self.p = p
        n = p["substeps"]
        self.h = p["ts"] / n
        self.coef = p["time_constant"] * self.h ** (-p["alpha"])
        size = 1 + n * 20000
        w = np.empty(size)
        w[0] = 1.0
        for j in range(1, size):
            w[j] = w[j - 1] * (1.0 - (p["alpha"] + 1.0) / j)
        self.w = w
        self.y = np.zeros(size)  # deviations from level0, newest last at index self.k
        self.k = 0
        self.queue = [0.0] * (p["delay_samples"] + 1)

    def step(self, setpoint):
        p = self.p
        self.queue.append(setpoint - p["setpoint0"])
        u = self.queue.pop(0)
        for _ in range(p["substeps"]):
            self.k += 1
            k = self.k
            # T h^-a (y_k + sum_{j>=1} w_j y_{k-j}) + y_k = K u
            history = np.dot(self.w[1:k + 1], self.y[k - 1::-1][:k])
            self.y[k] = (p["gain"] * u - self.coef * history) / (self.coef + 1.0)
        return p["q0"], p["q0"], p["level0"] + self.y[self.k]


class PlantContext(ModbusSlaveContext):
    def __init__(self, plant, setpoint0, **kwargs):
        super().__init__(**kwargs)
        self.plant = plant
        self.setpoint = setpoint0
        self.write_inputs(*plant.step(setpoint0), setpoint0)

    def write_inputs(self, q_in, q_out, level, position):
        block = self.store["i"]
        block.setValues(306, words(position))
        block.setValues(316, words(q_in) + words(q_out) + words(level))

    def getValues(self, fc_as_hex, address, count=1):
        if fc_as_hex == 4 and address <= LEVEL_ADDRESS < address + count:
            setpoint = setpoint_of(self)
            self.write_inputs(*self.plant.step(setpoint), setpoint)
        return super().getValues(fc_as_hex, address, count)


def main():
    port = int(sys.argv[1])
    params = json.loads(sys.argv[2])
    logging.basicConfig(level=logging.CRITICAL)
    plant = IdzPool(params) if params["kind"] == "idz" else FractionalFlume(params)
    holding = [0] * 400
    holding[300:302] = words(params["setpoint0"])
    store = PlantContext(plant, params["setpoint0"],
                         hr=ModbusSequentialDataBlock(0, holding),
                         ir=ModbusSequentialDataBlock(0, [0] * 400), zero_mode=True)
    context = ModbusServerContext(slaves=store, single=True)
    StartTcpServer(context=context, address=("127.0.0.1", port), allow_reuse_address=True)


if __name__ == "__main__":
    main()
