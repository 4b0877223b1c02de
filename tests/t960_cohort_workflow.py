#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# The cohort workflow (tools/cohort/Snakefile) end to end: the shipped label
# map and two variants made from it (the gallbladder removed, which the
# template marks optional; the colon and adrenal glands removed, so tissue
# takes their voxels) and a truncated file run with `--cores 2`; summary.csv
# has one row per case, the three complete with their figures, the corrupt one
# "prep failed" with fascia's error line naming its file. A rerun after one
# case's run.json is deleted redoes that run and the failed case only; with
# retry_failed=false nothing. The Slurm profile's dry run plans every job with
# the memory fascia's estimate gives.
# Usage: t960_cohort_workflow.py FASCIA SOURCE_DIR; exit 0 pass, 1 fail, 77 skip.
import csv
import gzip
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile

failures = 0


def check(cond, what):
    global failures
    if not cond:
        failures += 1
        print(f"t960: FAILED: {what}", file=sys.stderr)
    return cond


def relabel(source, target, drop):
    """A copy of a uint8 NIfTI-1 label map with the labels in drop set to 0."""
    raw = gzip.decompress(open(source, "rb").read())
    offset = int(struct.unpack_from("<f", raw, 108)[0])
    if struct.unpack_from("<h", raw, 70)[0] != 2:  # NIFTI_TYPE_UINT8
        sys.exit("t960: the shipped label map is not uint8; update relabel()")
    table = bytes(0 if v in drop else v for v in range(256))
    open(target, "wb").write(gzip.compress(raw[:offset] + raw[offset:].translate(table)))


def snakemake(source, cases, out, *extra, cwd):
    command = ["snakemake", "-s", os.path.join(source, "tools/cohort/Snakefile"), "--cores", "2", "--config",
               f"cases={cases}", f"scene={os.path.join(source, 'tools/cohort/abdomen-totalsegmentator-cohort.json')}",
               f"out={out}"] + list(extra)
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
    if done.returncode != 0:
        print(done.stdout[-3000:], done.stderr[-3000:], file=sys.stderr)
    return done


def times(out):
    stamp = {}
    for folder, _, files in os.walk(out):
        for name in files:
            path = os.path.join(folder, name)
            stamp[os.path.relpath(path, out)] = os.stat(path).st_mtime_ns
    return stamp


def main():
    fascia, source = sys.argv[1], sys.argv[2]
    if not shutil.which("snakemake"):
        print("t960: skipped: snakemake not installed (tools/setup/debian-packages.sh)")
        return 77
    work = tempfile.mkdtemp(prefix="fascia-t960-")
    cases, out = os.path.join(work, "cases"), os.path.join(work, "out")
    os.mkdir(cases)
    shipped = os.path.join(source, "data/labelmaps/totalsegmentator/example_seg.nii.gz")
    shutil.copy(shipped, os.path.join(cases, "shipped.nii.gz"))
    relabel(shipped, os.path.join(cases, "no-gallbladder.nii.gz"), {4})
    relabel(shipped, os.path.join(cases, "no-colon.nii.gz"), {8, 9, 20})
    with open(shipped, "rb") as f:
        open(os.path.join(cases, "corrupt.nii.gz"), "wb").write(f.read()[:6000])

    done = snakemake(source, cases, out, f"fascia={fascia}", cwd=work)
    check(done.returncode == 0, f"snakemake exit status {done.returncode}, expected 0 (a failed case fails alone)")
    with open(os.path.join(out, "summary.csv")) as f:
        rows = {row["case"]: row for row in csv.DictReader(f)}
    check(sorted(rows) == ["corrupt", "no-colon", "no-gallbladder", "shipped"], f"summary rows {sorted(rows)}")
    for case in ("shipped", "no-gallbladder", "no-colon"):
        row = rows.get(case, {})
        if not check(row.get("status") == "ok", f"{case}: status '{row.get('status')}' ({row.get('error')})"):
            continue
        check(int(row["frames"]) > 0 and int(row["samples"]) > 0, f"{case}: frames {row['frames']}")
        check(row["converged_steps"] == row["steps"] and int(row["steps"]) > 0,
              f"{case}: {row['converged_steps']} of {row['steps']} steps converged")
        check(float(row["ms_per_step"]) > 0 and float(row["max_strain"]) > 0, f"{case}: ms per step, strain")
        check(float(row.get("force_stomach_n") or 0) > 0, f"{case}: force on the stomach '{row.get('force_stomach_n')}'")
        check(float(row.get("volume_hepatic_cm3") or 0) > 0, f"{case}: hepatic volume")
        check(row["estimate_mib"] != "" and float(row["estimate_mib"]) >= float(row["prep_peak_mib"]),
              f"{case}: estimate {row['estimate_mib']} MiB below the measured peak {row['prep_peak_mib']} MiB")
        for name in ("model.h5", "results.h5", "run.json", "prep.json", "run.png", "history.csv"):
            check(os.path.exists(os.path.join(out, case, name)), f"{case}: {name} missing")
    if rows.get("shipped", {}).get("status") == "ok":
        shipped_row, gb, colon = rows["shipped"], rows["no-gallbladder"], rows["no-colon"]
        check(gb["absent_organs"] == "gallbladder" and shipped_row["absent_organs"] == "",
              f"absent organs '{gb['absent_organs']}', '{shipped_row['absent_organs']}'")
        check(gb["status"] != "ok" or int(gb["frames"]) < int(shipped_row["frames"]), "no gallbladder: fewer frames")
        check(gb.get("force_gallbladder_n", "") == "", "no gallbladder: no force on it")
        check(colon["status"] != "ok" or float(colon["tissue_volume_cm3"]) > float(shipped_row["tissue_volume_cm3"]),
              "no colon: more tissue")
    corrupt = rows.get("corrupt", {})
    check(corrupt.get("status") == "prep failed" and "corrupt.nii.gz" in corrupt.get("error", "")
          and "\n" not in corrupt.get("error", ""), f"corrupt: status '{corrupt.get('status')}', error "
          f"'{corrupt.get('error')}'")

    # a rerun redoes what is missing, and the failed case
    before = times(out)
    os.remove(os.path.join(out, "no-colon", "run.json"))
    done = snakemake(source, cases, out, f"fascia={fascia}", cwd=work)
    after = times(out)
    check(done.returncode == 0, f"rerun: exit status {done.returncode}")
    redone = sorted(k for k in after if after[k] != before.get(k))
    check("no-colon/run.json" in redone and "corrupt/prep.json" in redone and "summary.csv" in redone,
          f"rerun rewrote {redone}: expected no-colon's run, corrupt's prep and the summary")
    kept = ("shipped/", "no-gallbladder/", "no-colon/model.h5", "no-colon/prep.json", "no-colon/scene.json",
            "no-colon/estimate.json", "corrupt/scene.json", "corrupt/estimate.json")
    check(not [k for k in redone if k.startswith(kept)], f"rerun rewrote {redone}: more than what was missing")
    check(os.path.exists(os.path.join(out, "no-colon", "run.json")), "rerun: no-colon/run.json back")
    check(after.get("no-colon/model.h5") == before.get("no-colon/model.h5"), "rerun: no-colon's model redone")
    done = snakemake(source, cases, out, f"fascia={fascia}", "retry_failed=false", cwd=work)
    check(done.returncode == 0 and times(out) == after, "retry_failed=false: something was redone")
    # the corrupt file replaced by a good one: that case alone redone, then nothing
    shutil.copy(shipped, os.path.join(cases, "corrupt.nii.gz"))
    done = snakemake(source, cases, out, f"fascia={fascia}", cwd=work)
    fixed = times(out)
    redone = sorted(k for k in fixed if fixed[k] != after.get(k))
    check(done.returncode == 0 and not [k for k in redone if not k.startswith("corrupt/") and k != "summary.csv"]
          and "corrupt/model.h5" in redone, f"corrupt replaced: rewrote {redone}")
    with open(os.path.join(out, "summary.csv")) as f:
        status = {row["case"]: row["status"] for row in csv.DictReader(f)}
    check(status.get("corrupt") == "ok", f"corrupt replaced: status {status.get('corrupt')}")
    done = snakemake(source, cases, out, f"fascia={fascia}", cwd=work)
    check(done.returncode == 0 and times(out) == fixed, "after the repaired case: something was redone")

    # the cluster: the Slurm profile plans every job (dry run), the prep jobs with fascia's estimate
    fresh = os.path.join(work, "planned")
    os.mkdir(fresh)
    for name in ("shipped.nii.gz", "no-colon.nii.gz"):
        shutil.copy(os.path.join(cases, name), fresh)
    done = snakemake(source, fresh, os.path.join(work, "out-planned"), f"fascia={fascia}", "-n", "--profile",
                     os.path.join(source, "tools/cohort/slurm"), cwd=work)
    plan = done.stdout + done.stderr
    check(done.returncode == 0, "dry run with the Slurm profile failed")
    check(plan.count("rule prep:") == 2 and plan.count("rule run:") == 2 and "localrule summary:" in plan,
          "dry run: not every job planned")
    check(not os.path.exists(os.path.join(work, "out-planned")), "dry run wrote files")
    estimated = json.load(open(os.path.join(out, "shipped", "estimate.json")))
    check(estimated.get("peak_mib", 0) > 0, "estimate.json without peak_mib")

    if failures == 0:
        shutil.rmtree(work)
    else:
        print(f"t960: files kept in {work}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
