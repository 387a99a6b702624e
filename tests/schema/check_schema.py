#!/usr/bin/env python3
"""Checks schema/entities.schema.json with an independent validator against the C++ reader.

The validator is python3-jsonschema (Debian) or ajv-cli (npm). The schema must be a valid
draft-07 schema; every good document and every entity file under samples/ must validate; every
broken document must fail at the JSON pointer the C++ reader reports
(tests/data/schema/broken_expected.json), except rules JSON Schema cannot express (duplicate
ids, nesting depth), which the manifest marks and which must then pass the schema.

Python's json module reads NaN and Infinity, which are not JSON (RFC 8259); the check refuses
them as text, as ajv-cli's JSON.parse and the C++ reader do (docs/format.md tells users to do
the same). A number beyond a double (1e400) becomes infinity in both validators, which the
schema's bounds refuse at its pointer. A document that is not JSON for a validator must be one
the C++ reader refuses too.

usage: check_schema.py SCHEMA TEST_DATA_DIR SAMPLES_DIR [--ajv PATH_TO_AJV]
exit 0 when all agree, 1 on a disagreement, 77 when the asked-for validator is missing.
"""
import json
import pathlib
import re
import subprocess
import sys

SKIP = 77


def pointer(path):
    return "".join("/" + str(p).replace("~", "~0").replace("/", "~1") for p in path)


def refuse_constant(name):
    raise ValueError(f"{name} is not JSON")


def python_results(schema, paths):
    """{path: None (valid) | set of pointers | 'not json'} with python3-jsonschema."""
    import jsonschema

    jsonschema.Draft7Validator.check_schema(schema)
    validator = jsonschema.Draft7Validator(schema)
    results = {}
    for path in paths:
        try:
            # utf-8-sig: a leading byte order mark is skipped, as RFC 8259 8.1 allows.
            # NaN and Infinity are not JSON: refuse them as JSON.parse (ajv) and C++ do.
            document = json.loads(path.read_text(encoding="utf-8-sig"),
                                  parse_constant=refuse_constant)
        except ValueError:
            results[path] = "not json"
            continue
        errors = list(validator.iter_errors(document))
        if not errors:
            results[path] = None
            continue
        reported = set()
        for e in errors:
            base = pointer(e.absolute_path)
            if e.validator == "required":
                base += "/" + e.message.split("'")[1]
            reported.add(base)
        results[path] = reported
    return results


def strict_json(path):
    try:
        json.loads(path.read_text(encoding="utf-8-sig"), parse_constant=refuse_constant)
        return True
    except ValueError:
        return False


def ajv_run(ajv, schema_path, paths):
    command = [ajv, "validate", "--spec=draft7", "--all-errors", "--errors=json",
               "-s", str(schema_path)]
    for path in paths:
        command += ["-d", str(path)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    return done.stdout + done.stderr


def ajv_results(ajv, schema_path, paths):
    """The same with ajv-cli: one run for the texts that are JSON, one run for each other text
    (ajv-cli stops at the first file it cannot parse)."""
    batch = [p for p in paths if strict_json(p)]
    outputs = {p: ajv_run(ajv, schema_path, [p]) for p in paths if p not in batch}
    together = ajv_run(ajv, schema_path, batch) if batch else ""
    results = {}
    for path in paths:
        output = outputs.get(path, together)
        name = re.escape(str(path))
        found = re.search(rf"^{name} invalid\n(\[.*?\n\])$", output, re.M | re.S)
        if re.search(rf"^{name} valid$", output, re.M):
            results[path] = None
        elif found:
            reported = set()
            for e in json.loads(found.group(1)):
                base = e.get("instancePath", "")
                if e.get("keyword") == "required":
                    base += "/" + e["params"]["missingProperty"]
                reported.add(base)
            results[path] = reported
        elif path in outputs and output.startswith("error:"):
            results[path] = "not json"
        else:
            results[path] = f"no verdict in ajv's output: {output[-300:]!r}"
    return results


def main(argv):
    if len(argv) not in (3, 5):
        sys.exit(__doc__)
    schema_path, data_dir, samples_dir = (pathlib.Path(a) for a in argv[:3])
    ajv = argv[4] if len(argv) == 5 and argv[3] == "--ajv" else None
    if ajv is not None and not pathlib.Path(ajv).exists():
        print(f"SKIP ajv-cli not installed at {ajv} (scripts/install-deps.sh installs it)")
        return SKIP
    schema = json.loads(schema_path.read_text())

    good = sorted(pathlib.Path(data_dir, "good").glob("*.json"))
    # Entity files only: scene-render sensors' visibility/ records, sequence indexes
    # (sequence.json, checked against sequence.schema.json below) and 2D labels (labels-2d/)
    # are other formats.
    good += sorted(p for p in samples_dir.rglob("*.json")
                   if p.parent.name not in ("visibility", "labels-2d")
                   and p.name != "sequence.json")
    expected = json.loads(pathlib.Path(data_dir, "broken_expected.json").read_text())
    broken = sorted(pathlib.Path(data_dir, "broken").glob("*.json"))

    failures = []
    if sorted(expected) != [p.name for p in broken]:
        failures.append(f"broken_expected.json lists {sorted(expected)} but the folder has "
                        f"{[p.name for p in broken]}")
    results = (ajv_results(ajv, schema_path, good + broken) if ajv
               else python_results(schema, good + broken))

    for path in good:
        if results[path] is not None:
            failures.append(f"{path}: expected valid, got: {results[path]}")
    for path in broken:
        want = expected.get(path.name, {})
        got = results[path]
        if isinstance(got, str) and got != "not json":
            failures.append(f"{path.name}: {got}")
        elif got == "not json":
            continue  # refused as text, as the C++ reader refuses it
        elif not want.get("jsonschema_detects", True):
            if got is not None:
                failures.append(f"{path.name}: marked as beyond JSON Schema, but it fails: {got}")
        elif got is None:
            failures.append(f"{path.name}: expected invalid at {want.get('pointer')!r}, "
                            "but it validates")
        elif want.get("pointer") not in got:
            failures.append(f"{path.name}: expected an error at {want.get('pointer')!r}, "
                            f"got {sorted(got)}")

    sequence_schema = schema_path.with_name("sequence.schema.json")
    indexes = sorted(samples_dir.rglob("sequence.json"))
    if indexes:
        sequence = json.loads(sequence_schema.read_text())
        results = (ajv_results(ajv, sequence_schema, indexes) if ajv
                   else python_results(sequence, indexes))
        for path in indexes:
            if results[path] is not None:
                failures.append(f"{path}: expected a valid sequence index, got: {results[path]}")
    good += indexes

    for failure in failures:
        print("FAIL " + failure)
    checked = len(good) + len(broken)
    print(f"{'ajv-cli' if ajv else 'python3-jsonschema'}: {checked - len(failures)} passed, "
          f"{len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
