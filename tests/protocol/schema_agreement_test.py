#!/usr/bin/python3
"""Checks protocol/edit-batch.schema.json against tests/protocol/batches.json: the schema must be a
valid draft 2020-12 schema and give every case its table verdict (the C++ parser is held to the
same table by schema_agreement_test.cpp)."""
import json
import sys

from jsonschema import Draft202012Validator


def main(schema_path, table_path):
    with open(schema_path, encoding="utf-8") as f:
        schema = json.load(f)
    with open(table_path, encoding="utf-8") as f:
        cases = json.load(f)["cases"]
    Draft202012Validator.check_schema(schema)
    validator = Draft202012Validator(schema)
    failures = 0
    for case in cases:
        valid = validator.is_valid(case["batch"])
        if valid != case["valid"]:
            failures += 1
            errors = [e.message for e in validator.iter_errors(case["batch"])][:3]
            print(f"FAIL {case['name']}: schema says {'valid' if valid else 'invalid'} {errors}")
    print(f"{len(cases) - failures} passed, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
