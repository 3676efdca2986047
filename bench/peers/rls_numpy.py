#!/usr/bin/python3
"""Peer for `canalid identify --model arx --online --method exponential`: the same RLS loop in
numpy (Debian python3-numpy), sample by sample over a CSV, for the comparison in
bench/compare_online_numpy.sh.

ARX(2,2,1) in MATLAB's convention, y(t) + a1 y(t-1) + a2 y(t-2) = b1 u(t-1) + b2 u(t-2) + e(t),
regressor phi(t) = [-y(t-1), -y(t-2), u(t-1), u(t-2)], from t = 2.  Covariance form with
exponential forgetting, as core::RlsMethod::kExponential:
    e = y - phi' theta,  r = phi' P phi,  K = P phi / (lambda + r),  theta += K e,
    P <- (P - P phi phi' P / (lambda + r)) / lambda,  symmetrised,
with theta0 = 0 and P0 = 1e10 I (canalid's --online initial covariance).

Usage: rls_numpy.py DATA.csv [--u u] [--y y] [--forgetting L]
Prints {"a": [a1, a2], "b": [b1, b2]} as JSON.
"""
import argparse
import json

import numpy as np


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("csv")
    parser.add_argument("--u", default="u")
    parser.add_argument("--y", default="y")
    parser.add_argument("--forgetting", type=float, default=1.0)
    args = parser.parse_args()
    with open(args.csv) as f:
        header = f.readline().strip().split(",")
    data = np.loadtxt(args.csv, delimiter=",", skiprows=1)
    u = data[:, header.index(args.u)]
    y = data[:, header.index(args.y)]
    lam = args.forgetting
    theta = np.zeros(4)
    p = 1e10 * np.eye(4)
    for t in range(2, len(y)):
        phi = np.array([-y[t - 1], -y[t - 2], u[t - 1], u[t - 2]])
        pphi = p @ phi
        r = phi @ pphi
        e = y[t] - phi @ theta
        denom = lam + r
        theta = theta + pphi * (e / denom)
        p = (p - np.outer(pphi, pphi) / denom) / lam
        p = 0.5 * (p + p.T)
    print(json.dumps({"a": theta[:2].tolist(), "b": theta[2:].tolist()}))


if __name__ == "__main__":
    main()
