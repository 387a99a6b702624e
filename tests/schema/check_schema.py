#!/usr/bin/env python3
"""Checks schema/entities.schema.json with an independent validator (python3-jsonschema).

The schema must be a valid draft-07 schema; every good document and every entity file under
samples/ must validate; every broken document must fail at the JSON pointer the C++ validator
reports (tests/schema/data/broken_expected.json), except rules JSON Schema cannot express
(duplicate ids), which the manifest marks and which must then pass the schema.

usage: check_schema.py SCHEMA TEST_DATA_DIR SAMPLES_DIR
"""
import json
import pathlib
import sys

import jsonschema


def pointer(path):
    return "".join("/" + str(p).replace("~", "~0").replace("/", "~1") for p in path)


def error_pointers(error):
    """Pointers an error can be reported at: its path, and for 'required' the missing member."""
    base = pointer(error.absolute_path)
    if error.validator == "required":
        missing = error.message.split("'")[1]
        return {base + "/" + missing}
    return {base}


def main(schema_path, data_dir, samples_dir):
    schema = json.loads(pathlib.Path(schema_path).read_text())
    jsonschema.Draft7Validator.check_schema(schema)
    validator = jsonschema.Draft7Validator(schema)
    failures = []
    checked = 0

    good = sorted(pathlib.Path(data_dir, "good").glob("*.json"))
    # Entity files only: scene-render sensors' visibility/ records are another format.
    good += sorted(p for p in pathlib.Path(samples_dir).rglob("*.json")
                   if p.parent.name != "visibility")
    for path in good:
        checked += 1
        errors = list(validator.iter_errors(json.loads(path.read_text())))
        if errors:
            failures.append(f"{path}: expected valid, got: {errors[0].message}")

    expected = json.loads(pathlib.Path(data_dir, "broken_expected.json").read_text())
    broken = sorted(p.name for p in pathlib.Path(data_dir, "broken").glob("*.json"))
    if sorted(expected) != broken:
        failures.append(f"broken_expected.json lists {sorted(expected)} but the folder has {broken}")
    for name in broken:
        checked += 1
        want = expected.get(name, {})
        text = pathlib.Path(data_dir, "broken", name).read_text()
        try:
            document = json.loads(text, parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))
        except ValueError:
            if want.get("pointer") != "":
                failures.append(f"{name}: not JSON for Python, but the manifest expects a schema error")
            continue
        errors = list(validator.iter_errors(document))
        if not want.get("jsonschema_detects", True):
            if errors:
                failures.append(f"{name}: marked as beyond JSON Schema, but it fails: {errors[0].message}")
            continue
        if not errors:
            failures.append(f"{name}: expected invalid at {want.get('pointer')!r}, but it validates")
            continue
        reported = set().union(*(error_pointers(e) for e in errors))
        if want.get("pointer") not in reported:
            failures.append(f"{name}: expected an error at {want.get('pointer')!r}, got {sorted(reported)}")

    for failure in failures:
        print("FAIL " + failure)
    print(f"{checked - len(failures)} passed, {len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    sys.exit(main(*sys.argv[1:]))
