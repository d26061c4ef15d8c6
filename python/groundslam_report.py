#!/usr/bin/python3
"""Draws the paper's figures for a groundslam run folder and writes a self-contained report.html.

Usage: groundslam_report.py RUN_DIR [--compare ODOMETRY_RUN_DIR]
Reads the files `groundslam run` writes; needs only numpy and matplotlib (Debian's python3-* packages).
Exit status 2 with a message naming the file when an input is missing or malformed.
"""
import argparse
import base64
import csv
import html
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


class ReportError(Exception):
    """Bad input: the message names the file."""


# ---------------------------------------------------------------------------------------------- reading
def read_tum(path):
    """(timestamps, x, y, theta) of a TUM file."""
    if not os.path.exists(path):
        raise ReportError(f"{path}: no such file")
    rows = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            try:
                values = [float(v) for v in line.split()]
            except ValueError:
                raise ReportError(f"{path}:{number}: not a number in '{line}'")
            if len(values) != 8:
                raise ReportError(f"{path}:{number}: expected 8 numbers (t x y z qx qy qz qw), got {len(values)}")
            rows.append(values)
    if not rows:
        raise ReportError(f"{path}: no poses")
    a = np.array(rows)
    theta = 2.0 * np.arctan2(a[:, 6], a[:, 7])
    return a[:, 0], a[:, 1], a[:, 2], theta


# candidates.csv leaves these empty for candidates rejected before the fit.
EMPTY_WHEN_NOT_FITTED = ("covariance_score", "x", "y", "theta", "ambiguity")


def read_csv(path, required):
    if not os.path.exists(path):
        raise ReportError(f"{path}: no such file")
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        missing = [c for c in required if c not in (reader.fieldnames or [])]
        if missing:
            raise ReportError(f"{path}:1: missing columns {', '.join(missing)}")
        rows = list(reader)
    for number, row in enumerate(rows, 2):
        for column in required:
            value = row[column]
            if column in ("status", "rejected_by"):
                continue
            if value == "" and column in EMPTY_WHEN_NOT_FITTED:
                continue
            try:
                float(value)
            except ValueError:
                raise ReportError(f"{path}:{number}: column {column} is not a number: '{value}'")
    return rows


def column(rows, name):
    return np.array([float(r[name]) if r[name] != "" else np.nan for r in rows]) if rows else np.zeros(0)


def read_metrics(path):
    if not os.path.exists(path):
        return None
    try:
        with open(path) as f:
            return json.load(f)
    except json.JSONDecodeError as e:
        raise ReportError(f"{path}:{e.lineno}: malformed JSON: {e.msg}")


# ---------------------------------------------------------------------------------------------- helpers
def anchored(truth, estimate):
    """The estimate moved so that its first pose equals the first true pose (the paper's convention),
    restricted to the timestamps both share. Returns (t, truth xyθ, estimate xyθ)."""
    index = {round(t, 6): i for i, t in enumerate(truth[0])}
    pairs = [(i, index[round(t, 6)]) for i, t in enumerate(estimate[0]) if round(t, 6) in index]
    if not pairs:
        return None
    ie, it = np.array(pairs).T
    ex, ey, et = estimate[1][ie], estimate[2][ie], estimate[3][ie]
    gx, gy, gt = truth[1][it], truth[2][it], truth[3][it]
    rotation = gt[0] - et[0]
    c, s = math.cos(rotation), math.sin(rotation)
    x = c * (ex - ex[0]) - s * (ey - ey[0]) + gx[0]
    y = s * (ex - ex[0]) + c * (ey - ey[0]) + gy[0]
    return estimate[0][ie], (gx, gy, gt), (x, y, et + rotation)


def wrap(angle):
    return (angle + np.pi) % (2 * np.pi) - np.pi


def save(figure, path):
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


# ---------------------------------------------------------------------------------------------- figures
def figure_trajectory(run, truth, estimate, odometry, out):
    fig, ax = plt.subplots(figsize=(7, 6))
    if truth is not None:
        ax.plot(truth[1], truth[2], color="black", lw=2.0, label="ground truth")
        full = anchored(truth, estimate)
        if full:
            ax.plot(full[2][0], full[2][1], "r--", lw=1.4, label="groundslam (full SLAM)")
        if odometry is not None:
            odo = anchored(truth, odometry)
            if odo:
                ax.plot(odo[2][0], odo[2][1], "b:", lw=1.6, label="odometry only (no loop closure)")
    else:
        ax.plot(estimate[1], estimate[2], "r--", lw=1.4, label="groundslam (full SLAM)")
        if odometry is not None:
            ax.plot(odometry[1], odometry[2], "b:", lw=1.6, label="odometry only (no loop closure)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("Trajectory" + (" (first pose anchored to ground truth)" if truth is not None else ""))
    ax.grid(alpha=0.3)
    ax.legend(loc="best")
    return save(fig, os.path.join(out, "trajectory.png"))


def figure_loop_closures(estimate, loops, out):
    fig, ax = plt.subplots(figsize=(7, 6))
    ax.plot(estimate[1], estimate[2], color="0.3", lw=1.0, label="robot poses (groundslam)")
    a = column(loops, "frame_a").astype(int)
    b = column(loops, "frame_b").astype(int)
    for k, (i, j) in enumerate(zip(a, b)):
        ax.plot([estimate[1][i], estimate[1][j]], [estimate[2][i], estimate[2][j]], color="red", lw=0.8,
                alpha=0.7, label="accepted loop closure" if k == 0 else None)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"Loop closures: {len(loops)} accepted")
    ax.grid(alpha=0.3)
    ax.legend(loc="best")
    return save(fig, os.path.join(out, "loop_closures.png"))


def figure_threshold_scores(candidates, config, out):
    distance = column(candidates, "true_distance_m") * 100.0
    accepted = np.array([r["rejected_by"] == "none" for r in candidates])
    true = column(candidates, "footprints_overlap") > 0.5
    gates = config.get("loop_closure", {})
    panels = [("bow_score", "BoW score", gates.get("min_bow_score"), "min"),
              ("matches", "matched keypoints", gates.get("min_matches"), "min"),
              ("covariance_score", "covariance score log10(max eig Σ)", gates.get("max_covariance_score"), "max")]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    for ax, (key, label, threshold, kind) in zip(axes, panels):
        values = column(candidates, key)
        valid = np.isfinite(values) & (values > -1e9)
        if key == "matches":
            valid &= values >= 0
        styles = [(accepted & true, "o", "tab:green", "accepted, true loop"),
                  (accepted & ~true, "x", "red", "accepted, FALSE loop"),
                  (~accepted & true, "o", "tab:orange", "rejected, true loop"),
                  (~accepted & ~true, ".", "0.55", "rejected, false loop")]
        for mask, marker, color, name in styles:
            m = mask & valid
            ax.scatter(distance[m], values[m], s=12, marker=marker, color=color, label=f"{name} ({m.sum()})",
                       facecolors="none" if marker == "o" else None)
        if threshold is not None:
            ax.axhline(threshold, color="red", lw=1.2, ls="--", label=f"threshold ({kind} {threshold:g})")
        ax.set_xlabel("true distance between the two images (cm)")
        ax.set_ylabel(label)
        ax.set_title(label)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="best", fontsize=8)
    return save(fig, os.path.join(out, "threshold_scores.png"))


def figure_loop_accuracy(candidates, out):
    accepted = [r for r in candidates if r["rejected_by"] == "none"]
    estimated = np.hypot(column(accepted, "x"), column(accepted, "y")) * 100.0
    true = column(accepted, "true_distance_m") * 100.0
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.scatter(true, estimated, s=10, color="tab:blue", label=f"accepted loop closures ({len(accepted)})")
    top = max(1.0, float(np.max(np.concatenate([true, estimated]))) * 1.05) if len(accepted) else 1.0
    ax.plot([0, top], [0, top], "k--", lw=1.0, label="y = x")
    ax.set_xlim(0, top)
    ax.set_ylim(0, top)
    ax.set_aspect("equal")
    ax.set_xlabel("true distance between the two images (cm)")
    ax.set_ylabel("estimated distance of the loop transform (cm)")
    ax.set_title("Loop-closure accuracy")
    ax.grid(alpha=0.3)
    ax.legend(loc="best")
    return save(fig, os.path.join(out, "loop_accuracy.png"))


def figure_time(frames, out):
    index = column(frames, "index")
    stages = [c for c in ("load_ms", "extract_ms", "project_ms", "match_ms", "fit_ms", "loop_ms", "optimise_ms")]
    total = column(frames, "total_ms")
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    ax.stackplot(index, [column(frames, s) for s in stages], labels=[s.replace("_ms", "") for s in stages], alpha=0.85)
    mean = float(np.mean(total)) if len(total) else 0.0
    ax.axhline(mean, color="black", ls="--", lw=1.0,
               label=f"mean {mean:.1f} ms = {1000.0 / mean if mean > 0 else 0:.1f} frames/s")
    ax.set_ylabel("time per frame (ms)")
    ax.set_title("Processing time per frame, by stage")
    ax.legend(loc="upper left", fontsize=8, ncol=4)
    ax.grid(alpha=0.3)
    bx.plot(index, column(frames, "keypoints"), label="keypoints")
    bx.plot(index, column(frames, "inliers"), label="odometry inliers")
    bx.set_xlabel("frame")
    bx.set_ylabel("count")
    bx.legend(loc="best")
    bx.grid(alpha=0.3)
    return save(fig, os.path.join(out, "time.png"))


def figure_errors(truth, estimate, odometry, out):
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    for trajectory, name, style in ((estimate, "groundslam (full SLAM)", "r-"), (odometry, "odometry only", "b:")):
        if trajectory is None:
            continue
        paired = anchored(truth, trajectory)
        if not paired:
            continue
        t, g, e = paired
        ax.plot(t, np.hypot(e[0] - g[0], e[1] - g[1]) * 1000.0, style, lw=1.0, label=name)
        bx.plot(t, np.degrees(np.abs(wrap(e[2] - g[2]))), style, lw=1.0, label=name)
    ax.set_ylabel("translation error (mm)")
    ax.set_title("Error over the run (first pose anchored to ground truth)")
    bx.set_ylabel("rotation error (deg)")
    bx.set_xlabel("timestamp (frame index when the dataset has no time)")
    for a in (ax, bx):
        a.grid(alpha=0.3)
        a.legend(loc="best")
    return save(fig, os.path.join(out, "errors.png"))


# ---------------------------------------------------------------------------------------------- page
def metrics_rows(metrics, label):
    if not metrics:
        return ""
    names = [("translation_mae_cm_per_m", "translational MAE (cm/m)"), ("rotation_mae_deg", "rotational MAE (deg)"),
             ("ate_rmse_m", "ATE RMSE (m)"), ("rpe_translation_rmse_m", "RPE translation RMSE (m)"),
             ("rpe_rotation_rmse_deg", "RPE rotation RMSE (deg)"), ("fraction_estimated", "fraction of frames estimated"),
             ("fraction_measured", "fraction of frames measured (not assumed after an odometry failure)"),
             ("path_length_m", "path length (m)")]
    def shown(value):  # metrics.json writes null for a figure with nothing to compare
        return "n/a" if value is None else f"{value:.6g}"

    rows = "".join(f"<tr><td>{label}</td><td>{n}</td><td>{shown(metrics[k])}</td></tr>" for k, n in names if k in metrics)
    loops = metrics.get("loop_closure", {})
    rows += "".join(f"<tr><td>{label}</td><td>loop closures: {k.replace('_', ' ')}</td><td>{shown(v)}</td></tr>"
                    for k, v in loops.items())
    return rows


def write_html(run, figures, skipped, metrics, odometry_metrics, config_text, out):
    images = []
    for title, path in figures:
        with open(path, "rb") as f:
            data = base64.b64encode(f.read()).decode()
        images.append(f'<figure><img class="figure" alt="{html.escape(title)}" src="data:image/png;base64,{data}">'
                      f"<figcaption>{html.escape(title)}</figcaption></figure>")
    notes = "".join(f"<li>{html.escape(s)}</li>" for s in skipped)
    table = metrics_rows(metrics, "full SLAM") + metrics_rows(odometry_metrics, "odometry only")
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>groundslam report: {html.escape(os.path.basename(os.path.abspath(run)))}</title>
<style>body{{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}}img{{max-width:100%}}
table{{border-collapse:collapse}}td,th{{border:1px solid #bbb;padding:3px 8px;text-align:left}}
pre{{background:#f4f4f4;padding:1em;overflow-x:auto}}figure{{margin:2em 0}}</style></head>
<body><h1>groundslam report</h1><p>Run folder: <code>{html.escape(os.path.abspath(run))}</code></p>
<h2>Metrics</h2>
<table id="metrics"><tr><th>run</th><th>metric</th><th>value</th></tr>{table or '<tr><td colspan="3">no ground truth: no metrics</td></tr>'}</table>
<h2>Figures</h2>{''.join(images)}
{'<h2>Figures left out</h2><ul>' + notes + '</ul>' if notes else ''}
<h2>Configuration</h2><pre>{html.escape(config_text)}</pre>
<script>
// Marks the page for automated checks: how many figures have loaded with a non-zero size.
window.addEventListener("load", function () {{
  var shown = Array.prototype.filter.call(document.images, function (i) {{
    return i.complete && i.naturalWidth > 0 && i.getBoundingClientRect().width > 0; }});
  document.body.setAttribute("data-figures-shown", String(shown.length));
  document.body.setAttribute("data-figures-total", String(document.images.length));
}});
</script></body></html>
"""
    path = os.path.join(out, "report.html")
    with open(path, "w") as f:
        f.write(page)
    return path


def parse_config(path):
    """The run's config.yaml as nested dicts of scalars (enough for the threshold lines)."""
    if not os.path.exists(path):
        raise ReportError(f"{path}: no such file")
    config, section = {}, None
    with open(path) as f:
        text = f.read()
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if not line.startswith(" "):
            section = line.rstrip(":").strip()
            config[section] = {}
            continue
        if ":" not in line or section is None:
            raise ReportError(f"{path}:{number}: not a 'key: value' line")
        key, value = line.split(":", 1)
        try:
            config[section][key.strip()] = float(value)
        except ValueError:
            config[section][key.strip()] = value.strip()
    return config, text


def report(run, compare):
    if not os.path.isdir(run):
        raise ReportError(f"{run}: no such run folder")
    out = os.path.join(run, "report")
    os.makedirs(out, exist_ok=True)
    config, config_text = parse_config(os.path.join(run, "config.yaml"))
    estimate = read_tum(os.path.join(run, "trajectory.tum"))
    truth_path = os.path.join(run, "groundtruth.tum")
    truth = read_tum(truth_path) if os.path.exists(truth_path) else None
    odometry_dir = compare or os.path.join(run, "odometry")
    odometry = read_tum(os.path.join(odometry_dir, "trajectory.tum")) if os.path.exists(
        os.path.join(odometry_dir, "trajectory.tum")) else None
    if compare and odometry is None:
        raise ReportError(f"{os.path.join(compare, 'trajectory.tum')}: no such file")
    frames = read_csv(os.path.join(run, "frames.csv"),
                      ["index", "keypoints", "inliers", "load_ms", "extract_ms", "project_ms", "match_ms", "fit_ms",
                       "loop_ms", "optimise_ms", "total_ms"])
    loops = read_csv(os.path.join(run, "loop_closures.csv"), ["frame_a", "frame_b", "x", "y", "theta"])
    candidates_path = os.path.join(run, "candidates.csv")
    candidates = read_csv(candidates_path, ["frame_a", "frame_b", "bow_score", "matches", "covariance_score",
                                            "rejected_by", "x", "y"])
    has_truth_columns = candidates and "true_distance_m" in candidates[0] and candidates[0]["true_distance_m"] != ""
    if has_truth_columns:
        candidates = read_csv(candidates_path, ["true_distance_m", "footprints_overlap"])
    metrics = read_metrics(os.path.join(run, "metrics.json"))
    odometry_metrics = read_metrics(os.path.join(odometry_dir, "metrics.json"))

    figures, skipped = [], []
    figures.append(("1. Trajectory: ground truth, full SLAM and odometry alone", figure_trajectory(run, truth, estimate, odometry, out)))
    if odometry is None:
        skipped.append("Figure 1 has no odometry-only line: run with --report, or give --compare DIR of a --no-loop-closure run.")
    if loops:
        figures.append(("2. Loop closures (red: accepted loop closure between two poses)", figure_loop_closures(estimate, loops, out)))
    else:
        skipped.append("2. Loop closures: this run accepted no loop closure.")
    if has_truth_columns and candidates:
        figures.append(("3. Threshold scores of every verified candidate against the true distance",
                        figure_threshold_scores(candidates, config, out)))
    else:
        skipped.append("3. Threshold scores: needs ground truth and verified loop-closure candidates.")
    if has_truth_columns and loops:
        figures.append(("4. Loop-closure accuracy: estimated against true distance", figure_loop_accuracy(candidates, out)))
    else:
        skipped.append("4. Loop accuracy: needs ground truth and accepted loop closures.")
    figures.append(("5. Processing time per frame and stage; keypoints and inliers", figure_time(frames, out)))
    if truth is not None:
        figures.append(("6. Translational and rotational error over the run", figure_errors(truth, estimate, odometry, out)))
    else:
        skipped.append("6. Error over the run: the dataset has no ground truth.")
    return write_html(run, figures, skipped, metrics, odometry_metrics, config_text, run), [p for _, p in figures], skipped


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run_dir")
    parser.add_argument("--compare", help="run folder of an odometry-only (--no-loop-closure) run")
    args = parser.parse_args()
    try:
        page, figures, skipped = report(args.run_dir, args.compare)
    except ReportError as e:
        print(f"groundslam report: error: {e}", file=sys.stderr)
        return 2
    for path in figures:
        print(f"figure: {path}")
    for line in skipped:
        print(f"left out: {line}")
    print(f"report: {page}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
