#!/usr/bin/env python3
"""Prints a libFuzzer dictionary for the JSON targets: every property name and string constant
of the job and gains schemas (docs/*.schema.json, which `ftctune schema` keeps current), and the
JSON tokens and numbers at the edges the loaders check."""
import json
import sys

words = set()


def walk(node):
    if isinstance(node, dict):
        for key, value in node.items():
            if key == "properties" and isinstance(value, dict):
                words.update(value)
            elif key == "enum" and isinstance(value, list):
                words.update(v for v in value if isinstance(v, str))
            elif key == "const" and isinstance(value, str):
                words.add(value)
            walk(value)
    elif isinstance(node, list):
        for value in node:
            walk(value)


for path in sys.argv[1:]:
    with open(path, encoding="utf-8") as f:
        walk(json.load(f))
words.add("ftctune.scenarios/1")
words.add("recoverable")

tokens = ["{", "}", "[", "]", ":", ",", "null", "true", "false", "-0", "0.5", "1e308",
          "1e309", "-1e308", "5e-324", "2.2250738585072014e-308", "9007199254740993",
          "18446744073709551615", "18446744073709551616", "-9223372036854775808",
          "\\u0000", "\\ud800", "\\\""]
for word in sorted(words):
    print(json.dumps(json.dumps(word)))
for token in tokens:
    print(json.dumps(token))
