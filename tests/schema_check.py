#!/usr/bin/python3
"""Validates JSON files against a JSON Schema (draft 2020-12) with python3-jsonschema.

usage: schema_check.py SCHEMA FILE...  -> one line per file, "ok" or its first errors;
exit 0 when every file is valid, 1 otherwise, 2 when the schema itself is not valid.
"""
import json
import sys

import jsonschema

schema = json.load(open(sys.argv[1]))
try:
    jsonschema.Draft202012Validator.check_schema(schema)
except jsonschema.SchemaError as e:
    print(f"invalid schema: {e.message}")
    sys.exit(2)
validator = jsonschema.Draft202012Validator(schema)
status = 0
for path in sys.argv[2:]:
    errors = sorted(validator.iter_errors(json.load(open(path))), key=lambda e: list(e.path))
    if errors:
        status = 1
        where = "/" + "/".join(str(p) for p in errors[0].path)
        print(f"{path}: invalid at {where}: {errors[0].message[:200]}")
    else:
        print(f"{path}: ok")
sys.exit(status)
