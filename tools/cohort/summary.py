#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# The cohort's table (tools/cohort/Snakefile): one row per case from its
# records (prep.json, run.json, estimate.json beside each other), written as
# CSV under a temporary name and renamed. Columns that depend on the scene
# (tissue volumes, organ forces) are the union over the cases; a case
# without one leaves it empty. docs/cohort.md lists the columns.
import csv
import json
import math
import os
import sys


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        return {"exit_status": 1, "error": f"record '{path}' unreadable: {e}"}


def number(value, scale=1.0, digits=6):
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        return ""
    return f"{value * scale:.{digits}g}"


def row_of(folder):
    case = os.path.basename(folder)
    prep = load(os.path.join(folder, "prep.json"))
    run = load(os.path.join(folder, "run.json"))
    estimate = load(os.path.join(folder, "estimate.json"))
    row = {"case": case}
    if prep.get("exit_status") != 0:
        row["status"] = "prep failed"
        row["error"] = prep.get("error") or "fascia prep failed without a message"
    elif run.get("exit_status") != 0:
        row["status"] = "run failed"
        row["error"] = run.get("error") or "fascia run failed without a message"
    else:
        row["status"] = "ok"
        row["error"] = ""
    row["absent_organs"] = " ".join(prep.get("absent_organs") or [])
    row["dropped_tissues"] = " ".join(prep.get("dropped_tissues") or [])
    row["frames"] = prep.get("frames", "")
    row["samples"] = prep.get("samples", "")
    row["tissue_volume_cm3"] = number(prep.get("tissue_volume"), 1e6)
    volumes = {}
    for tissue in prep.get("tissues") or []:
        volumes[f"volume_{tissue.get('name')}_cm3"] = number(tissue.get("volume"), 1e6)
    row["steps"] = run.get("steps", "")
    row["dt_s"] = run.get("dt", "")
    row["converged_steps"] = run.get("converged_steps", "")
    row["ms_per_step"] = number(run.get("ms_per_step"), 1, 4)
    row["max_strain"] = number(run.get("max_strain"))
    row["max_stress_pa"] = number(run.get("max_stress"))
    row["max_displacement_mm"] = number((run.get("displacement") or {}).get("max"), 1e3)
    forces = {}
    for organ, force in (run.get("organ_force") or {}).items():
        end = (force or {}).get("end")
        if isinstance(end, list) and len(end) == 3:
            forces[f"force_{organ}_n"] = number(math.sqrt(sum(c * c for c in end)))
    row["prep_seconds"] = number(prep.get("wall_seconds"), 1, 4)
    row["run_seconds"] = number(run.get("wall_seconds"), 1, 4)
    row["prep_peak_mib"] = number((prep.get("peak_rss_bytes") or 0) / 1048576 or None, 1, 4)
    row["estimate_mib"] = estimate.get("peak_mib", "") if estimate.get("exit_status") == 0 else ""
    return row, volumes, forces


def main():
    out, records = sys.argv[1], sys.argv[2:]
    rows, volume_keys, force_keys = [], set(), set()
    for path in records:
        row, volumes, forces = row_of(os.path.dirname(os.path.abspath(path)))
        rows.append((row, volumes, forces))
        volume_keys.update(volumes)
        force_keys.update(forces)
    first = ["case", "status", "error", "absent_organs", "dropped_tissues", "frames", "samples", "tissue_volume_cm3"]
    middle = ["steps", "dt_s", "converged_steps", "ms_per_step", "max_strain", "max_stress_pa", "max_displacement_mm"]
    last = ["prep_seconds", "run_seconds", "prep_peak_mib", "estimate_mib"]
    header = first + sorted(volume_keys) + middle + sorted(force_keys) + last
    tmp = f"{out}.tmp-{os.getpid()}"
    with open(tmp, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=header, restval="")
        writer.writeheader()
        for row, volumes, forces in rows:
            writer.writerow({**row, **volumes, **forces})
    os.replace(tmp, out)


if __name__ == "__main__":
    main()
