#!/usr/bin/env python3
"""Parses a Prometheus text exposition with the reference parser (Debian's
python3-prometheus-client) and prints every sample as JSON lines: {"family", "type", "name",
"labels", "value"}. Exits 1 with the parser's message when the text does not parse.

Usage: parse_metrics.py METRICS_FILE
"""
import json
import math
import sys

try:
    from prometheus_client.parser import text_string_to_metric_families
except ImportError:
    sys.exit("prometheus_client is missing: install Debian's python3-prometheus-client "
             "(scripts/setup)")


def main():
    with open(sys.argv[1], encoding="utf-8") as f:
        text = f.read()
    try:
        families = list(text_string_to_metric_families(text))
    except Exception as error:  # the parser raises ValueError and others on bad input
        sys.exit(f"{sys.argv[1]}: not the Prometheus text format: {error}")
    for family in families:
        for sample in family.samples:
            value = None if math.isnan(sample.value) else sample.value
            print(json.dumps({"family": family.name, "type": family.type, "name": sample.name,
                              "labels": sample.labels, "value": value}))


if __name__ == "__main__":
    main()
