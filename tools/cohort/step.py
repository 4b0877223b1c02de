#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# One step of a cohort case (tools/cohort/Snakefile): writes the case's scene
# from the template, or runs `fascia prep` / `fascia run` with --json and
# keeps its JSON as the step's record. A case that fails is data, not a
# workflow error: the record holds fascia's error line and this script exits
# 0, so the other cases go on and the summary has the failed case's row.
# Every file is written under a temporary name and renamed when complete.
import json
import math
import os
import resource
import subprocess
import sys
import time


def write_atomic(path, text):
    tmp = f"{path}.tmp-{os.getpid()}"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def write_json(path, record):
    write_atomic(path, json.dumps(record, indent=1) + "\n")


def absolute(path, folder):
    return path if os.path.isabs(path) else os.path.normpath(os.path.join(folder, path))


def make_scene(template, segmentation, out):
    """The template with its segmentation replaced; its other relative paths
    (a label table, meshes) made absolute, as the case's scene lies elsewhere."""
    with open(template) as f:
        scene = json.load(f)
    folder = os.path.dirname(os.path.abspath(template))
    seg = scene.get("segmentation")
    if not isinstance(seg, dict):
        sys.exit(f"cohort: template scene '{template}': no \"segmentation\" object; a cohort scene builds its "
                 "organs from labels (docs/cohort.md)")
    seg["file"] = os.path.abspath(segmentation)
    labels = seg.get("labels")
    if isinstance(labels, str) and ":" not in labels:
        seg["labels"] = absolute(labels, folder)
    for item in scene.get("organs", []) + scene.get("tissues", []):
        if isinstance(item, dict) and isinstance(item.get("mesh"), str):
            item["mesh"] = absolute(item["mesh"], folder)
    scene.pop("output", None)
    write_json(out, scene)


def motion_end(scene_path):
    """The time the scene's last prescribed motion ends (0: none)."""
    with open(scene_path) as f:
        scene = json.load(f)
    end = 0.0
    for organ in scene.get("organs", []):
        for key in (organ.get("motion") or {}).get("keys", []):
            end = max(end, float(key.get("time", 0)))
    return end


def fascia_json(command, log):
    """Runs fascia with --json; its record, with the wall time and peak memory."""
    start = time.monotonic()
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    with open(log, "w") as err:
        done = subprocess.run(command, stdout=subprocess.PIPE, stderr=err, text=True)
    seconds = time.monotonic() - start
    record = None
    for line in reversed(done.stdout.splitlines()):
        try:
            record = json.loads(line)
            break
        except ValueError:
            continue
    if not isinstance(record, dict):
        if done.returncode < 0:
            error = f"{command[0]} {command[1]} was killed by signal {-done.returncode} (out of memory?); see {log}"
        else:
            error = f"{command[0]} {command[1]} ended with status {done.returncode} and no JSON; see {log}"
        record = {"exit_status": done.returncode, "error": error}
    record["wall_seconds"] = seconds
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    if peak > before:  # kilobytes on Linux; the largest child so far
        record["peak_rss_bytes"] = 1024 * peak
    record["command_line"] = " ".join(command)
    return record


def pictures(history, folder):
    """Strain and solver work over time, with gnuplot; a warning when it fails."""
    png = os.path.join(folder, "run.png")
    tmp = os.path.join(folder, f"run.tmp-{os.getpid()}.png")
    script = (f"set terminal pngcairo size 900,600; set output '{tmp}'; set datafile separator ',';"
              "set multiplot layout 2,1; set xlabel 'time (s)'; set ylabel 'largest strain'; set key off;"
              f"plot '{history}' using 2:8 every ::1 with lines lw 2;"
              "set ylabel 'Newton iterations'; "
              f"plot '{history}' using 2:5 every ::1 with impulses lw 2; unset multiplot")
    try:
        done = subprocess.run(["gnuplot", "-e", script], capture_output=True, text=True)
    except OSError as e:
        return f"pictures: gnuplot not run ({e})"
    if done.returncode != 0 or not os.path.exists(tmp):
        if os.path.exists(tmp):
            os.remove(tmp)
        return f"pictures: gnuplot failed: {done.stderr.strip().splitlines()[-1:] or done.returncode}"
    os.replace(tmp, png)
    return None


def main():
    what = sys.argv[1]
    if what == "scene":
        template, segmentation, out = sys.argv[2:5]
        make_scene(template, segmentation, out)
    elif what == "estimate":
        fascia, scene, out = sys.argv[2:5]
        write_json(out, fascia_json([fascia, "prep", scene, "--estimate", "--json"],
                                    os.path.join(os.path.dirname(out), "estimate.log")))
    elif what == "prep":
        fascia, scene, model, threads, out, attempt = sys.argv[2:8]
        record = fascia_json([fascia, "prep", scene, "-o", model, "--json", "--threads", threads],
                             os.path.join(os.path.dirname(out), "prep.log"))
        record["attempt"] = int(attempt)
        write_json(out, record)
    elif what == "run":
        fascia, scene, prep_json, threads, dt, seconds, out, attempt = sys.argv[2:10]
        extra = sys.argv[10:]
        folder = os.path.dirname(out)
        with open(prep_json) as f:
            prep = json.load(f)
        if prep.get("exit_status") != 0:
            write_json(out, {"command": "cohort", "ended": "not run", "exit_status": 1, "attempt": int(attempt),
                             "error": "not run: fascia prep failed (prep.json)"})
            return
        dt = float(dt)
        seconds = float(seconds) if seconds else 1.5 * motion_end(scene)
        steps = max(1, math.ceil(seconds / dt - 1e-9))
        history = os.path.join(folder, "history.csv")
        command = [fascia, "run", prep["output"], "--steps", str(steps), "--dt", repr(dt), "--json",
                   "--threads", threads, "-o", os.path.join(folder, "results.h5"), "--history", history] + extra
        record = fascia_json(command, os.path.join(folder, "run.log"))
        record["attempt"] = int(attempt)
        if record.get("exit_status") == 0 and os.path.exists(history):
            warning = pictures(history, folder)
            if warning:
                record["pictures_warning"] = warning
        write_json(out, record)
    else:
        sys.exit(f"step.py: unknown step '{what}' (known: scene, estimate, prep, run)")


if __name__ == "__main__":
    main()
