#!/usr/bin/python3
"""Checks a run's per-frame odometry and mount estimates against a simulated sequence's ground truth.

Usage: scripts/motion_check.py RUN_DIR SEQUENCE_DIR [--json]
Prints: frames whose status is ok but whose odometry motion is off by more than 5 mm or 0.5 degrees
(silent wrong motions), the same count among the frames flagged as less certain (low_overlap, sharp_turn,
gap, aligned, unconfirmed, uncertain), the RMS error of the estimated roll, pitch and height (mount.csv), and the
graph's edges between frames that are not consecutive (bridges over a loss, loop closures, as graph.g2o holds them
after the run) that are off by more than a wrong loop closure is: 2 cm or 2 degrees.
"""
import csv
import json
import math
import os
import sys


def read_tum(path):
    poses = {}
    for line in open(path):
        if line.startswith('#') or not line.strip():
            continue
        t, x, y, _z, qx, qy, qz, qw = map(float, line.split()[:8])
        poses[round(t)] = (x, y, 2.0 * math.atan2(qz, qw))
    return poses


def between(a, b):
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return (c * dx + s * dy, -s * dx + c * dy, math.atan2(math.sin(b[2] - a[2]), math.cos(b[2] - a[2])))


def motion_error(row, gt):
    """A frames.csv row's odometry motion against the true one: metres, degrees."""
    theta = math.radians(float(row['odometry_theta_deg']))
    dm = math.hypot(float(row['odometry_x_m']) - gt[0], float(row['odometry_y_m']) - gt[1])
    return dm, abs(math.degrees(math.atan2(math.sin(theta - gt[2]), math.cos(theta - gt[2]))))


def wrong_graph_edges(run, truth, frames):
    """graph.g2o's edges between frames that are not consecutive, and how many are off by > 2 cm or 2 degrees.
    The graph's last vertices are frames.csv's rows in order (a prior map's keyframes come first); each is matched to
    the truth by its timestamp. Edges without information (a prior map's anchors) are not measurements."""
    checked, wrong = 0, 0
    path = run + '/graph.g2o'
    if not os.path.exists(path):
        return checked, wrong
    lines = [line.split() for line in open(path)]
    vertices = sum(1 for f in lines if f and f[0] == 'VERTEX_SE2')
    offset = vertices - len(frames)
    key = lambda v: round(float(frames[v - offset]['timestamp'])) if 0 <= v - offset < len(frames) else None
    for f in lines:
        if not f or f[0] != 'EDGE_SE2' or not any(float(x) != 0.0 for x in f[6:12]):
            continue
        i, j = key(int(f[1])), key(int(f[2]))
        if abs(int(f[2]) - int(f[1])) == 1 or i not in truth or j not in truth:
            continue
        gt = between(truth[i], truth[j])
        x, y, theta = map(float, f[3:6])
        checked += 1
        off_deg = abs(math.degrees(math.atan2(math.sin(theta - gt[2]), math.cos(theta - gt[2]))))
        wrong += 1 if math.hypot(x - gt[0], y - gt[1]) > 0.02 or off_deg > 2.0 else 0
    return checked, wrong


def main():
    run, seq = sys.argv[1], sys.argv[2]
    truth = read_tum(seq + '/groundtruth.tum')
    # mount.csv: written by simulate since the outdoor options; older sequences have none (no tilt figures).
    mounts = {int(r['index']): r for r in csv.DictReader(open(seq + '/mount.csv'))} if os.path.exists(seq + '/mount.csv') else {}
    frames = list(csv.DictReader(open(run + '/frames.csv')))
    wrong, ok, worst_m, worst_deg = 0, 0, 0.0, 0.0
    low, low_wrong = 0, 0
    flagged = {'sharp_turn': [0, 0], 'gap': [0, 0], 'aligned': [0, 0], 'unconfirmed': [0, 0], 'uncertain': [0, 0]}  # frames, off
    tilt_err, height_err, tilt_level = [], [], []
    for prev, row in zip(frames, frames[1:]):
        i, j = int(prev['index']), int(row['index'])
        if row['status'] == 'low_overlap' and i in truth and j in truth:
            low += 1
            dm, dd = motion_error(row, between(truth[i], truth[j]))
            low_wrong += 1 if dm > 0.005 or dd > 0.5 else 0
        if row['status'] in flagged and i in truth and j in truth:
            dm, dd = motion_error(row, between(truth[i], truth[j]))
            flagged[row['status']][0] += 1
            flagged[row['status']][1] += 1 if dm > 0.005 or dd > 0.5 else 0
        if row['status'] == 'ok' and i in truth and j in truth:
            ok += 1
            dm, dd = motion_error(row, between(truth[i], truth[j]))
            worst_m, worst_deg = max(worst_m, dm), max(worst_deg, dd)
            if dm > 0.005 or dd > 0.5:
                wrong += 1
        if row.get('mount_estimated') == '1' and j in mounts:
            m = mounts[j]
            tilt_err += [float(row['roll_deg']) - float(m['roll_deg']), float(row['pitch_deg']) - float(m['pitch_deg'])]
            tilt_level += [float(m['roll_deg']), float(m['pitch_deg'])]
            height_err.append(float(row['height_m']) - float(m['height_m']))
    edges_checked, edges_wrong = wrong_graph_edges(run, truth, frames)
    rms = lambda v: math.sqrt(sum(x * x for x in v) / len(v)) if v else float('nan')
    result = {'ok_frames': ok, 'silent_wrong_motions': wrong, 'worst_ok_error_mm': 1000 * worst_m,
              'worst_ok_error_deg': worst_deg, 'low_overlap_frames': low, 'low_overlap_off': low_wrong,
              'sharp_turn_frames': flagged['sharp_turn'][0], 'sharp_turn_off': flagged['sharp_turn'][1],
              'gap_frames': flagged['gap'][0], 'gap_off': flagged['gap'][1],
              'aligned_frames': flagged['aligned'][0], 'aligned_off': flagged['aligned'][1],
              'unconfirmed_frames': flagged['unconfirmed'][0], 'unconfirmed_off': flagged['unconfirmed'][1],
              'uncertain_frames': flagged['uncertain'][0], 'uncertain_off': flagged['uncertain'][1],
              'mount_estimated_frames': len(height_err),
              'tilt_rms_error_deg': rms(tilt_err), 'tilt_rms_true_deg': rms(tilt_level),
              'height_rms_error_mm': 1000 * rms(height_err),
              'graph_edges_checked': edges_checked, 'wrong_graph_edges': edges_wrong}
    if '--json' in sys.argv:
        print(json.dumps(result))
    else:
        for k, v in result.items():
            print(f'{k:24s} {v:.4g}' if isinstance(v, float) else f'{k:24s} {v}')


if __name__ == '__main__':
    main()
