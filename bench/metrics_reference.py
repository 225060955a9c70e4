#!/usr/bin/env python3
"""Python/numpy port of the reference dance-evaluation metrics, timed against `dancegen eval`.

    metrics_reference.py --set bench/.metrics-set [--binary target/release/dancegen] [--reps 5]
                         [--protocols none,finedance-lodge] [--out bench/.metrics-set/results.json]

The port is written from the formulas (crates/dancegen-metrics module docs and
../shared/reference/anchors.md section A), reproducing the reference implementations as they are:
pure-Python loops where the reference loops (fairmotion-style kinetic features with the
acceleration precedence bug, Bailando `manual_new` per-frame predicates, GCD group / per-frame
kinetic features, all-pairs diversity), numpy where the reference is vectorised (Bailando BAS
`calc_db`, EDGE PFC, LODGE foot skating, SoulDance MPJPE, Duolando cross-distance feature), and the
libraries the references call (`scipy.linalg.sqrtm` in the Bailando / mint FID,
`scipy.ndimage.gaussian_filter` + `scipy.signal.argrelextrema` in BAS / BED,
`dtaidistance.dtw_ndim.warping_paths` + `dtw.best_path` in GMC). `freeze` and `boundary_jerk` are
our own definitions (crates/dancegen-metrics/src/longform.rs), written in plain numpy. TIF has no
reference code and is not ported (skipped).

Inputs are read as `dancegen eval` reads them: the float32 `.npy` files converted to float64, then
the protocol (`none`: as given, kinetic frame time 1/fps; `finedance-lodge`: first 1024 frames,
frame-0 root subtracted, joints 1.. relative to the current root, kinetic features cut to 66-d,
frame time 1/60). Kinetic and manual features are cast to float32 as the references store them,
and the Bailando / mint normalisation then runs in float32 on them, as in the reference.

Timing: each metric group is timed on its own (time.perf_counter, loading excluded and reported
separately, features of pred and GT included). With --binary, the same groups are run through
`dancegen eval` as separate processes (wall time incl. process start and file loading; median of
--reps runs), the whole suite once more in one process, and the values are cross-checked.
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
import warnings

import numpy as np
from scipy import linalg
from scipy.ndimage import gaussian_filter as G
from scipy.signal import argrelextrema

FPS = 30.0

# ----------------------------------------------------------------------------------------------
# Kinetic features (fairmotion / AIST++ API / Bailando copy), loops as in the reference.


def calc_average_velocity_horizontal(positions, i, joint_idx, sliding_window, frame_time):
    current_window = 0
    average_velocity = np.zeros(len(positions[0][joint_idx]))
    for j in range(-sliding_window, sliding_window + 1):
        if i + j - 1 < 0 or i + j >= len(positions):
            continue
        average_velocity += positions[i + j][joint_idx] - positions[i + j - 1][joint_idx]
        current_window += 1
    average_velocity = average_velocity / (current_window * frame_time)
    return np.linalg.norm(np.array([average_velocity[0], average_velocity[2]]))  # up = y


def calc_average_velocity_vertical(positions, i, joint_idx, sliding_window, frame_time):
    current_window = 0
    average_velocity = np.zeros(len(positions[0][joint_idx]))
    for j in range(-sliding_window, sliding_window + 1):
        if i + j - 1 < 0 or i + j >= len(positions):
            continue
        average_velocity += positions[i + j][joint_idx] - positions[i + j - 1][joint_idx]
        current_window += 1
    average_velocity = average_velocity / (current_window * frame_time)
    return np.abs(average_velocity[1])


def calc_average_acceleration(positions, i, joint_idx, sliding_window, frame_time, fixed=False):
    current_window = 0
    average_acceleration = np.zeros(len(positions[0][joint_idx]))
    for j in range(-sliding_window, sliding_window + 1):
        if i + j - 1 < 0 or i + j + 1 >= len(positions):
            continue
        v2 = (positions[i + j + 1][joint_idx] - positions[i + j][joint_idx]) / frame_time
        if fixed:  # aioz-ai/GCD
            v1 = (positions[i + j][joint_idx] - positions[i + j - 1][joint_idx]) / frame_time
        else:  # the reference's operator-precedence bug
            v1 = positions[i + j][joint_idx] - positions[i + j - 1][joint_idx] / frame_time
        average_acceleration += (v2 - v1) / frame_time
        current_window += 1
    return np.linalg.norm(average_acceleration / max(current_window, 1))


def extract_kinetic_features(positions, frame_time):
    """(T, 24, 3) -> 72 float32: per joint [E_h, E_v, A] (window 2, precedence bug)."""
    T = positions.shape[0]
    out = []
    for joint in range(positions.shape[1]):
        eh = 0.0
        for i in range(1, T):
            eh += calc_average_velocity_horizontal(positions, i, joint, 2, frame_time) ** 2
        ev = 0.0
        for i in range(1, T):
            ev += calc_average_velocity_vertical(positions, i, joint, 2, frame_time) ** 2
        ee = 0.0
        for i in range(1, T):
            ee += calc_average_acceleration(positions, i, joint, 2, frame_time)
        out += [eh / (T - 1), ev / (T - 1), ee / (T - 1)]
    return np.array(out, dtype=np.float32)


# ----------------------------------------------------------------------------------------------
# Geometric ("manual_new") features, per-frame predicates as in the reference.

SMPL_JOINT_NAMES = ["root", "lhip", "rhip", "belly", "lknee", "rknee", "spine", "lankle", "rankle",
                    "chest", "ltoes", "rtoes", "neck", "linshoulder", "rinshoulder", "head",
                    "lshoulder", "rshoulder", "lelbow", "relbow", "lwrist", "rwrist", "lhand", "rhand"]
_REST = {"lshoulder": [1.99113488e-01, 2.36807942e-01, -1.80702247e-02],
         "lelbow": [4.54445392e-01, 2.21158922e-01, -4.10167128e-02],
         "rshoulder": [-1.91692337e-01, 2.36928746e-01, -1.23055102e-02],
         "lhip": [5.64076714e-02, -3.23069185e-01, 1.09197125e-02],
         "rhip": [-6.24834076e-02, -3.31302464e-01, 1.50412619e-02]}


def distance_between_points(a, b):
    return np.linalg.norm(np.array(a) - np.array(b))


def distance_from_plane(a, b, c, p, threshold):
    ba = np.array(b) - np.array(a)
    ca = np.array(c) - np.array(a)
    cross = np.cross(ca, ba)
    pa = np.array(p) - np.array(a)
    return np.dot(cross, pa) / np.linalg.norm(cross) > threshold


def distance_from_plane_normal(n1, n2, a, p, threshold):
    normal = np.array(n2) - np.array(n1)
    pa = np.array(p) - np.array(a)
    return np.dot(normal, pa) / np.linalg.norm(normal) > threshold


def angle_within_range(j1, j2, k1, k2, range_):
    j = np.array(j2) - np.array(j1)
    k = np.array(k2) - np.array(k1)
    with np.errstate(invalid="ignore", divide="ignore"):
        angle = np.arccos(np.dot(j, k) / (np.linalg.norm(j) * np.linalg.norm(k)))
    angle = np.degrees(angle)
    return range_[0] < angle < range_[1]


def velocity_direction_above_threshold(j1, j1_prev, j2, j2_prev, p, p_prev, threshold,
                                       time_per_frame=1 / 120):
    velocity = np.array(p) - np.array(j1) - (np.array(p_prev) - np.array(j1_prev))
    direction = np.array(j2) - np.array(j1)
    velocity_along_direction = np.dot(velocity, direction) / np.linalg.norm(direction)
    velocity_along_direction = velocity_along_direction / time_per_frame
    return velocity_along_direction > threshold


def velocity_direction_above_threshold_normal(j1, j1_prev, j2, j3, p, p_prev, threshold,
                                              time_per_frame=1 / 120):
    velocity = np.array(p) - np.array(j1) - (np.array(p_prev) - np.array(j1_prev))
    j31 = np.array(j3) - np.array(j1)
    j21 = np.array(j2) - np.array(j1)
    direction = np.cross(j31, j21)
    velocity_along_direction = np.dot(velocity, direction) / np.linalg.norm(direction)
    velocity_along_direction = velocity_along_direction / time_per_frame
    return velocity_along_direction > threshold


def velocity_above_threshold(p, p_prev, threshold, time_per_frame=1 / 120):
    velocity = np.linalg.norm(np.array(p) - np.array(p_prev)) / time_per_frame
    return velocity > threshold


class ManualFeatures:
    def __init__(self, positions, joint_names=SMPL_JOINT_NAMES):
        self.positions = positions
        self.joint_names = joint_names
        self.frame_num = 1
        self.hl = distance_between_points(_REST["lshoulder"], _REST["lelbow"])
        self.sw = distance_between_points(_REST["lshoulder"], _REST["rshoulder"])
        self.hw = distance_between_points(_REST["lhip"], _REST["rhip"])

    def next_frame(self):
        self.frame_num += 1

    def transform_and_fetch_position(self, j):
        if j == "y_unit":
            return [0, 1, 0]
        if j == "minus_y_unit":
            return [0, -1, 0]
        if j == "zero":
            return [0, 0, 0]
        if j == "y_min":
            return [0, min([y for (_, y, _) in self.positions[self.frame_num]]), 0]
        return self.positions[self.frame_num][self.joint_names.index(j)]

    def transform_and_fetch_prev_position(self, j):
        return self.positions[self.frame_num - 1][self.joint_names.index(j)]

    def f_move(self, j1, j2, j3, j4, range_):
        j1_prev, j2_prev, j3_prev = [self.transform_and_fetch_prev_position(j) for j in [j1, j2, j3]]
        j1, j2, j3 = [self.transform_and_fetch_position(j) for j in [j1, j2, j3]]
        return velocity_direction_above_threshold(j1, j1_prev, j2, j2_prev, j3, j3_prev, range_)

    def f_nmove(self, j1, j2, j3, j4, range_):
        j1_prev, j4_prev = [self.transform_and_fetch_prev_position(j) for j in [j1, j4]]
        j1, j2, j3, j4 = [self.transform_and_fetch_position(j) for j in [j1, j2, j3, j4]]
        return velocity_direction_above_threshold_normal(j1, j1_prev, j2, j3, j4, j4_prev, range_)

    def f_plane(self, j1, j2, j3, j4, threshold):
        j1, j2, j3, j4 = [self.transform_and_fetch_position(j) for j in [j1, j2, j3, j4]]
        return distance_from_plane(j1, j2, j3, j4, threshold)

    def f_nplane(self, j1, j2, j3, j4, threshold):
        j1, j2, j3, j4 = [self.transform_and_fetch_position(j) for j in [j1, j2, j3, j4]]
        return distance_from_plane_normal(j1, j2, j3, j4, threshold)

    def f_angle(self, j1, j2, j3, j4, range_):
        j1, j2, j3, j4 = [self.transform_and_fetch_position(j) for j in [j1, j2, j3, j4]]
        return angle_within_range(j1, j2, j3, j4, range_)

    def f_fast(self, j1, threshold):
        j1_prev = self.transform_and_fetch_prev_position(j1)
        j1 = self.transform_and_fetch_position(j1)
        return velocity_above_threshold(j1, j1_prev, threshold)


def extract_manual_features(positions):
    features = []
    f = ManualFeatures(positions)
    hl, sw, hw = f.hl, f.sw, f.hw
    for _ in range(1, positions.shape[0]):
        pf = []
        pf.append(f.f_nmove("neck", "rhip", "lhip", "rwrist", 1.8 * hl))
        pf.append(f.f_nmove("neck", "lhip", "rhip", "lwrist", 1.8 * hl))
        pf.append(f.f_nplane("chest", "neck", "neck", "rwrist", 0.2 * hl))
        pf.append(f.f_nplane("chest", "neck", "neck", "lwrist", 0.2 * hl))
        pf.append(f.f_move("belly", "chest", "chest", "rwrist", 1.8 * hl))
        pf.append(f.f_move("belly", "chest", "chest", "lwrist", 1.8 * hl))
        pf.append(f.f_angle("relbow", "rshoulder", "relbow", "rwrist", [0, 110]))
        pf.append(f.f_angle("lelbow", "lshoulder", "lelbow", "lwrist", [0, 110]))
        pf.append(f.f_nplane("lshoulder", "rshoulder", "lwrist", "rwrist", 2.5 * sw))
        pf.append(f.f_move("lwrist", "rwrist", "rwrist", "lwrist", 1.4 * hl))
        pf.append(f.f_move("rwrist", "root", "lwrist", "root", 1.4 * hl))
        pf.append(f.f_move("lwrist", "root", "rwrist", "root", 1.4 * hl))
        pf.append(f.f_fast("rwrist", 2.5 * hl))
        pf.append(f.f_fast("lwrist", 2.5 * hl))
        pf.append(f.f_plane("root", "lhip", "ltoes", "rankle", 0.38 * hl))
        pf.append(f.f_plane("root", "rhip", "rtoes", "lankle", 0.38 * hl))
        pf.append(f.f_nplane("zero", "y_unit", "y_min", "rankle", 1.2 * hl))
        pf.append(f.f_nplane("zero", "y_unit", "y_min", "lankle", 1.2 * hl))
        pf.append(f.f_nplane("lhip", "rhip", "lankle", "rankle", 2.1 * hw))
        pf.append(f.f_angle("rknee", "rhip", "rknee", "rankle", [0, 110]))
        pf.append(f.f_angle("lknee", "lhip", "lknee", "lankle", [0, 110]))
        pf.append(f.f_fast("rankle", 2.5 * hl))
        pf.append(f.f_fast("lankle", 2.5 * hl))
        pf.append(f.f_angle("neck", "root", "rshoulder", "relbow", [25, 180]))
        pf.append(f.f_angle("neck", "root", "lshoulder", "lelbow", [25, 180]))
        pf.append(f.f_angle("neck", "root", "rhip", "rknee", [50, 180]))
        pf.append(f.f_angle("neck", "root", "lhip", "lknee", [50, 180]))
        pf.append(f.f_plane("rankle", "neck", "lankle", "root", 0.5 * hl))
        pf.append(f.f_angle("neck", "root", "zero", "y_unit", [70, 110]))
        pf.append(f.f_nplane("zero", "minus_y_unit", "y_min", "rwrist", -1.2 * hl))
        pf.append(f.f_nplane("zero", "minus_y_unit", "y_min", "lwrist", -1.2 * hl))
        pf.append(f.f_fast("root", 2.3 * hl))
        features.append(pf)
        f.next_frame()
    return np.array(features, dtype=np.float32).mean(axis=0)


# ----------------------------------------------------------------------------------------------
# FID / diversity: Bailando metrics_new (quantized_metrics) and mint / GCD.


def normalize(feat, feat2):
    mean = feat.mean(axis=0)
    std = feat.std(axis=0)
    return (feat - mean) / (std + 1e-10), (feat2 - mean) / (std + 1e-10)


def _sqrtm(a):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return linalg.sqrtm(a, disp=False)


def calc_fid(kps_gen, kps_gt, eps=1e-5):
    mu1, mu2 = np.mean(kps_gen, axis=0), np.mean(kps_gt, axis=0)
    sigma1, sigma2 = np.cov(kps_gen, rowvar=False), np.cov(kps_gt, rowvar=False)
    diff = mu1 - mu2
    covmean, _ = _sqrtm(sigma1.dot(sigma2))
    if not np.isfinite(covmean).all():
        offset = np.eye(sigma1.shape[0]) * eps
        covmean, _ = _sqrtm((sigma1 + offset).dot(sigma2 + offset))
    tr_covmean = np.trace(covmean)
    # Bailando returns the complex value as is; the real part is what every paper reports.
    return float(np.real(diff.dot(diff) + np.trace(sigma1) + np.trace(sigma2) - 2 * tr_covmean))


def calculate_avg_distance(feature_list):
    feature_list = np.stack(feature_list)
    n = feature_list.shape[0]
    dist = 0
    for i in range(n):
        for j in range(i + 1, n):
            dist += np.linalg.norm(feature_list[i] - feature_list[j])
    dist /= (n * n - n) / 2
    return float(dist)


def mint_frechet_feature_distance(real, generated, eps=1e-6):
    """GCD calculate_gmr_scores: normalise both with the real set, mint FD (eps 1e-6)."""
    real, generated = np.stack(real), np.stack(generated)
    mean = np.mean(real, axis=0)
    std = np.std(real, axis=0) + 1e-10
    real = (real - mean) / std
    generated = (generated - mean) / std
    mu1, mu2 = np.mean(real, axis=0), np.mean(generated, axis=0)
    sigma1, sigma2 = np.cov(real, rowvar=False), np.cov(generated, rowvar=False)
    diff = mu1 - mu2
    covmean, _ = _sqrtm(sigma1.dot(sigma2))
    if not np.isfinite(covmean).all():
        offset = np.eye(sigma1.shape[0]) * eps
        covmean = _sqrtm((sigma1 + offset).dot(sigma2 + offset))[0]
    if np.iscomplexobj(covmean):
        if not np.allclose(np.diagonal(covmean).imag, 0, atol=1e-3):
            raise ValueError("Imaginary component {}".format(np.max(np.abs(covmean.imag))))
        covmean = covmean.real
    fd = diff.dot(diff) + np.trace(sigma1) + np.trace(sigma2) - 2 * np.trace(covmean)
    return float(fd), calculate_avg_distance(generated)


# ----------------------------------------------------------------------------------------------
# Beat align score (Bailando utils/beat_align_score.py).


def calc_db(keypoints):
    keypoints = np.array(keypoints).reshape(-1, 24, 3)
    kinetic_vel = np.mean(np.sqrt(np.sum((keypoints[1:] - keypoints[:-1]) ** 2, axis=2)), axis=1)
    kinetic_vel = G(kinetic_vel, 5)
    motion_beats = argrelextrema(kinetic_vel, np.less)
    return motion_beats, len(kinetic_vel)


def BA(music_beats, motion_beats):
    if len(music_beats) == 0 or len(motion_beats[0]) == 0:
        return None  # the reference raises (ZeroDivisionError / np.min of an empty array)
    ba = 0
    for bb in music_beats:
        ba += np.exp(-np.min((motion_beats[0] - bb) ** 2) / 2 / 9)
    return float(ba / len(music_beats))


def bas_clip(joints, beats):
    motion_beats, length = calc_db(joints)
    return BA(beats[beats < length], motion_beats)  # get_mb(key, length): beats < T - 1


# ----------------------------------------------------------------------------------------------
# PFC (EDGE eval/eval_pfc.py), on the Z-up rotation (x, -z, y) of the Y-up joints.


def pfc_clip(joints_yup):
    joint3d = np.stack([joints_yup[..., 0], -joints_yup[..., 2], joints_yup[..., 1]], axis=-1)
    up_dir = 2
    flat_dirs = [i for i in range(3) if i != up_dir]
    DT = 1 / 30
    root_v = (joint3d[1:, 0, :] - joint3d[:-1, 0, :]) / DT
    root_a = (root_v[1:] - root_v[:-1]) / DT
    root_a[:, up_dir] = np.maximum(root_a[:, up_dir], 0)
    root_a = np.linalg.norm(root_a, axis=-1)
    scaling = root_a.max()
    if not (np.isfinite(scaling) and scaling > 0):
        return None  # the reference gives NaN
    root_a /= scaling
    feet = joint3d[:, [7, 10, 8, 11]]
    foot_v = np.linalg.norm(feet[2:, :, flat_dirs] - feet[1:-1, :, flat_dirs], axis=-1)
    foot_mins = np.zeros((len(foot_v), 2))
    foot_mins[:, 0] = np.minimum(foot_v[:, 0], foot_v[:, 1])
    foot_mins[:, 1] = np.minimum(foot_v[:, 2], foot_v[:, 3])
    return float((foot_mins[:, 0] * foot_mins[:, 1] * root_a).mean())


# ----------------------------------------------------------------------------------------------
# Foot-skating ratio (LODGE metric/foot_skating.py) on positions, ground_height = 0.

_F32 = lambda x: float(np.float32(x))


def fsr_clip(joints):
    ltoe, rtoe = joints[0, 10, 1], joints[0, 11, 1]
    h = (ltoe + rtoe) / 2 if abs(ltoe - rtoe) < _F32(0.02) else min(ltoe, rtoe)
    feet = joints[:, [7, 8, 10, 11]].copy()  # l ankle, r ankle, l toe, r toe
    feet[..., 1] -= h
    ratios = []
    for ankle, toe in ((0, 2), (1, 3)):
        contact = (feet[:, ankle, 1] <= _F32(0.08)) & (feet[:, toe, 1] <= _F32(0.05))
        vel = np.zeros((len(feet), 2, 3))
        vel[:-1] = feet[1:, [ankle, toe]] - feet[:-1, [ankle, toe]]
        vel[~contact] = 0
        tangent = np.abs((vel[..., 0] + vel[..., 2]) / 2)
        sliding = (tangent > _F32(0.01)).any(axis=1) & contact
        with np.errstate(invalid="ignore", divide="ignore"):
            ratios.append(np.float32(sliding.sum()) / np.float32(contact.sum()))
    r = (float(ratios[0]) + float(ratios[1])) / 2
    return r if math.isfinite(r) else None


# ----------------------------------------------------------------------------------------------
# MPJPE (SoulDance utils/metrics.py calculate_mpjpe), 24 joints.


def mpjpe_clip(gt, pred):
    n = min(len(gt), len(pred))
    gt, pred = gt[:n], pred[:n]
    gt = gt - gt[:, :1]
    pred = pred - pred[:, :1]
    return float(np.linalg.norm(pred - gt, axis=-1).mean(axis=-1).mean())


# ----------------------------------------------------------------------------------------------
# Our long-form metrics (longform.rs): freeze and boundary jerk (boundaries every 150 frames).


def freeze_clip(joints, fps):
    speeds = fps * np.linalg.norm(joints[1:] - joints[:-1], axis=-1).mean(axis=1)
    w = max(1, int(round(fps)))
    windows = len(speeds) // w
    if windows == 0:
        return None
    thr = 0.05 * np.median(speeds)
    means = speeds[:windows * w].reshape(windows, w).mean(axis=1)
    return float(((means < thr) | (means == 0)).sum() / windows)


def boundary_jerk_clip(joints, fps, every=150):
    T = len(joints)
    bounds = list(range(every, T, every))
    if not bounds:
        return None
    jerk = fps ** 3 * np.linalg.norm(joints[3:] - 3 * joints[2:-1] + 3 * joints[1:-2] - joints[:-3],
                                     axis=-1).mean(axis=1)
    n = len(jerk)
    band = np.zeros(n, dtype=bool)
    for b in bounds:
        band[max(b - 4, 0):min(b, n - 1) + 1] = True
    if n == 0 or band.all() or not band.any() or jerk[~band].sum() == 0:
        return None
    return float(jerk[band].mean() / jerk[~band].mean())


# ----------------------------------------------------------------------------------------------
# Group metrics (aioz-ai/GCD): group kinetic features (GMR), per-frame kinetic features + DTW (GMC).


def _vel_hv(positions, i, joint, window, frame_time):
    return (calc_average_velocity_horizontal(positions, i, joint, window, frame_time),
            calc_average_velocity_vertical(positions, i, joint, window, frame_time))


def extract_group_kinetic_features(scene, frame_time=1 / 30, window=1, m=1.5):
    N, T = scene.shape[0], scene.shape[1]
    out = []
    for joint in range(24):
        eh = 0.0
        for n in range(N):
            for i in range(1, T):
                eh += calc_average_velocity_horizontal(scene[n], i, joint, window, frame_time) ** 2
        ev = 0.0
        for n in range(N):
            for i in range(1, T):
                ev += calc_average_velocity_vertical(scene[n], i, joint, window, frame_time) ** 2
        ee = 0.0
        for n in range(N):
            for i in range(1, T):
                ee += calc_average_acceleration(scene[n], i, joint, window, frame_time, fixed=True)
        out += [np.log(1 + m * (eh / (T - 1) / N)), np.log(1 + m * (ev / (T - 1) / N)),
                np.log(1 + m * (ee / (T - 1) / N))]
    return np.array(out, dtype=np.float32)


def extract_kinetic_features_per_frame(positions, frame_time=1 / 30, window=2, m=1.5):
    T = positions.shape[0]
    feats = []
    for i in range(1, T):
        row = []
        for joint in range(24):
            h = calc_average_velocity_horizontal(positions, i, joint, window, frame_time) ** 2
            v = calc_average_velocity_vertical(positions, i, joint, window, frame_time) ** 2
            e = calc_average_acceleration(positions, i, joint, window, frame_time, fixed=True)
            row += [np.log(1 + m * h), np.log(1 + m * v), np.log(1 + m * e)]
        feats.append(row)
    return np.array(feats)


def gmc_scene(scene):
    from dtaidistance import dtw, dtw_ndim
    N, T = scene.shape[0], scene.shape[1]
    feats = [extract_kinetic_features_per_frame(scene[n]) for n in range(N)]
    vals = []
    for n1 in range(N):
        for n2 in range(n1 + 1, N):
            _, paths = dtw_ndim.warping_paths(scene[n1], scene[n2])
            path = dtw.best_path(paths)
            val, pp = 0.0, 0
            for t1, t2 in path:
                if t1 >= T - 1 or t2 >= T - 1:
                    continue
                val += np.dot(feats[n1][t1], feats[n2][t2])
                pp += 1
            if pp == 0:
                return None
            vals.append(val / pp)
    return float(np.mean(vals)) if vals else None


# ----------------------------------------------------------------------------------------------
# Duet metrics (lisiyao21/Duolando utils/metrics_duet.py).

DUET_KEY_JOINTS = [0, 7, 8, 10, 11, 15, 16, 17, 20, 21]
SMPLX55_FROM_SMPL24 = list(range(22)) + [15] * 3 + [22] * 15 + [23] * 15


def duet_feature(follower, leader):
    T = min(len(follower), len(leader))
    f, l = follower[:T, DUET_KEY_JOINTS], leader[:T, DUET_KEY_JOINTS]
    d = np.sqrt(((f[:, :, None, :] - l[:, None, :, :]) ** 2).sum(axis=-1))  # (T, 10, 10)
    return d.reshape(T, -1).mean(axis=0)


def calc_db55(joints24):
    k = joints24[:, SMPLX55_FROM_SMPL24]
    kinetic_vel = np.mean(np.sqrt(np.sum((k[1:] - k[:-1]) ** 2, axis=2)), axis=1)
    kinetic_vel = G(kinetic_vel, 5)
    return argrelextrema(kinetic_vel, np.less)


def bed_pair(follower, leader):
    return BA(calc_db55(leader)[0], calc_db55(follower))


# ----------------------------------------------------------------------------------------------
# Protocols, loading.


def prepare(joints, protocol):
    if protocol == "aistpp-bailando":
        z = joints[:1200]
        return z - z[0, 0], 1 / 60, 72
    if protocol == "finedance-lodge":
        z = joints[:1024].copy()
        z = z - z[0, 0]
        z[:, 1:] -= z[:, :1]
        return z, 1 / 60, 66
    return joints, 1 / FPS, 72  # none: as given, frame time 1/fps (30 fps here)


def load_dir(d):
    names = sorted(f for f in os.listdir(d) if f.endswith(".npy"))
    return [(n[:-4], np.load(os.path.join(d, n)).astype(np.float64)) for n in names]


def _mean(vals):
    vals = [v for v in vals if v is not None]
    return sum(vals) / len(vals) if vals else None


def timed(fn):
    t = time.perf_counter()
    r = fn()
    return r, (time.perf_counter() - t) * 1e3


# ----------------------------------------------------------------------------------------------
# Metric groups: each returns ({key: value}, {key: [per-clip values]}).


def solo_groups(pred, gt, beats, protocol, fps=FPS):
    P = [(s, *prepare(j, protocol)) for s, j in pred]
    Gt = [(s, *prepare(j, protocol)) for s, j in gt]
    gt_by = {s: j for s, j, _, _ in Gt}

    def fid_div(kind):
        def run():
            if kind == "k":
                fp = np.stack([extract_kinetic_features(j, ft)[:dims] for _, j, ft, dims in P])
                fg = np.stack([extract_kinetic_features(j, ft)[:dims] for _, j, ft, dims in Gt])
            else:
                fp = np.stack([extract_manual_features(j) for _, j, _, _ in P])
                fg = np.stack([extract_manual_features(j) for _, j, _, _ in Gt])
            gn, pn = normalize(fg, fp)
            return {f"fid_{kind}": calc_fid(pn, gn), f"div_{kind}": calculate_avg_distance(pn),
                    f"div_{kind}_gt": calculate_avg_distance(gn)}, {}
        return run

    def per_clip(key, fn):
        def run():
            vals = [fn(s, j) for s, j, _, _ in P]
            out = {key: _mean(vals)}
            if key == "pfc" and out[key] is not None:
                out[key] *= 10000
            if key == "bas":
                out["bas_gt"] = _mean([fn(s, j) for s, j, _, _ in Gt])
            return out, {key: vals}
        return run

    return {
        "fid_k,div_k": fid_div("k"),
        "fid_g,div_g": fid_div("g"),
        "bas": per_clip("bas", lambda s, j: bas_clip(j, beats)),
        "pfc": per_clip("pfc", lambda s, j: pfc_clip(j)),
        "fsr": per_clip("fsr", lambda s, j: fsr_clip(j)),
        "mpjpe": per_clip("mpjpe", lambda s, j: mpjpe_clip(gt_by[s], j) if s in gt_by else None),
        "freeze": per_clip("freeze", lambda s, j: freeze_clip(j, fps)),
        "boundary_jerk": per_clip("boundary_jerk", lambda s, j: boundary_jerk_clip(j, fps)),
    }


def group_groups(pred_scenes, gt_scenes):
    def gmr():
        fg = [extract_group_kinetic_features(s) for _, s in gt_scenes]
        fp = [extract_group_kinetic_features(s) for _, s in pred_scenes]
        v, _div = mint_frechet_feature_distance(fg, fp)  # dancegen computes Dist_k too, does not report it
        return {"gmr": v}, {}

    def gmc():
        vals = [gmc_scene(s) for _, s in pred_scenes]
        return {"gmc": _mean(vals)}, {"gmc": vals}

    return {"gmr": gmr, "gmc": gmc, "tif": None}


def duet_groups(pred_f, pred_l, gt_f, gt_l):
    pl, gl = dict(pred_l), dict(gt_l)

    def fid_div():
        fp = np.stack([duet_feature(f, pl[s]) for s, f in pred_f])
        fg = np.stack([duet_feature(f, gl[s]) for s, f in gt_f])
        gn, pn = normalize(fg, fp)
        return {"fid_cd": calc_fid(pn, gn), "div_cd": calculate_avg_distance(pn),
                "div_cd_gt": calculate_avg_distance(gn)}, {}

    def bed():  # generated pairs only, as `dancegen eval` reports it (no bed_gt)
        vals = [bed_pair(f, pl[s]) for s, f in pred_f]
        return {"bed": _mean(vals)}, {"bed": vals}

    return {"fid_cd,div_cd": fid_div, "bed": bed}


# ----------------------------------------------------------------------------------------------
# Rust side and comparison.


def rust_run(binary, args, reps):
    times, out = [], None
    with tempfile.TemporaryDirectory() as td:
        js = os.path.join(td, "out.json")
        for _ in range(reps):
            t = time.perf_counter()
            r = subprocess.run([binary, "-q", "eval", *args, "--json", js], stdout=subprocess.DEVNULL,
                               stderr=subprocess.PIPE, text=True)
            times.append((time.perf_counter() - t) * 1e3)
            if r.returncode != 0:
                print(f"  dancegen eval {' '.join(args)} failed: {r.stderr.strip()}", file=sys.stderr)
                return None, None
        with open(js) as f:
            out = json.load(f)
    return statistics.median(times), out


def rel_diff(a, b):
    if a is None or b is None:
        return 0.0 if (a is None and b is None) else math.inf
    m = max(abs(a), abs(b))
    return 0.0 if m == 0 else abs(a - b) / m


def compare(py_vals, py_clips, rust_json, key_map=None):
    """Worst relative difference per metric key: set values and per-clip values."""
    key_map = key_map or {}
    worst = {}
    for k, v in py_vals.items():
        rk = key_map.get(k, k)
        if rk not in rust_json:
            worst[k] = None
            continue
        worst[k] = rel_diff(v, rust_json[rk])
    rows = rust_json.get("per_clip", [])
    for k, vals in py_clips.items():
        rk = key_map.get(k, k)
        rv = [r.get(rk) for r in rows]
        if len(rv) != len(vals):
            continue
        w = max([rel_diff(a, b) for a, b in zip(vals, rv)] or [0.0])
        worst[k] = max(worst.get(k) or 0.0, w)
    return worst


def fmt_ms(x):
    return "-" if x is None else (f"{x:,.0f}" if x >= 100 else f"{x:.1f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--set", required=True)
    ap.add_argument("--binary")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--protocols", default="none,finedance-lodge,aistpp-bailando",
                    help="solo protocols; aistpp-bailando runs on the 60-fps set (solo60/, beats60.npy)")
    ap.add_argument("--no-group", action="store_true", help="skip the group / duet part")
    ap.add_argument("--out")
    args = ap.parse_args()
    S = args.set
    out = {"threads": {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")},
           "numpy": np.__version__, "scipy": __import__("scipy").__version__, "runs": []}

    (pred, gt, beats), load_ms = timed(lambda: (load_dir(f"{S}/solo/pred"), load_dir(f"{S}/solo/gt"),
                                                 np.load(f"{S}/beats.npy").astype(np.int64)))
    out["python_load_ms"] = {"solo": load_ms}
    table = []  # (section, group, py_ms, rust_ms, worst)

    def run_section(section, groups, rust_args_for, key_map=None):
        total_py, py_all_vals, py_all_clips, worst_all = 0.0, {}, {}, {}
        for name, fn in groups.items():
            if fn is None:  # Rust only (no reference to port): timed, not compared
                if args.binary:
                    rust_ms, _ = rust_run(args.binary, rust_args_for(name), args.reps)
                    table.append((section, name + " (Rust only)", None, rust_ms, None))
                continue
            (vals, clips), py_ms = timed(fn)
            total_py += py_ms
            py_all_vals.update(vals)
            py_all_clips.update(clips)
            rust_ms, worst = None, None
            if args.binary:
                rust_ms, rj = rust_run(args.binary, rust_args_for(name), args.reps)
                if rj is not None:
                    worst = compare(vals, clips, rj, key_map)
                    worst_all.update(worst)
            table.append((section, name, py_ms, rust_ms, worst))
            out["runs"].append({"section": section, "metrics": name, "python_ms": py_ms, "rust_ms": rust_ms,
                                "python": vals, "python_per_clip": clips, "worst_rel_diff": worst})
            print(f"  {section:<22} {name:<16} python {fmt_ms(py_ms):>8} ms   rust {fmt_ms(rust_ms):>7} ms",
                  file=sys.stderr, flush=True)
        rust_ms = None
        if args.binary:
            all_metrics = ",".join(k for k, fn in groups.items() if fn is not None)
            rust_ms, rj = rust_run(args.binary, rust_args_for(all_metrics), max(1, min(args.reps, 3)))
            rj = rj or {}
            worst = compare(py_all_vals, py_all_clips, rj, key_map)
            out["runs"].append({"section": section, "metrics": "ALL", "python_ms": total_py, "rust_ms": rust_ms,
                                "rust": {k: v for k, v in rj.items() if k != "per_clip"},
                                "worst_rel_diff": worst})
        table.append((section, "whole suite", total_py, rust_ms, None))

    for protocol in args.protocols.split(","):
        if protocol == "aistpp-bailando":
            d, fps, bf = "solo60", 60.0, "beats60.npy"
            (p60, g60, b60), ms = timed(lambda: (load_dir(f"{S}/{d}/pred"), load_dir(f"{S}/{d}/gt"),
                                                 np.load(f"{S}/{bf}").astype(np.int64)))
            out["python_load_ms"]["solo60"] = ms
            groups = solo_groups(p60, g60, b60, protocol, fps)
        else:
            d, fps, bf = "solo", FPS, "beats.npy"
            groups = solo_groups(pred, gt, beats, protocol, fps)
        run_section(f"solo {protocol}", groups,
                    lambda m, p=protocol, d=d, fps=fps, bf=bf: [
                        "--pred", f"{S}/{d}/pred", "--gt", f"{S}/{d}/gt", "--protocol", p, "--fps", f"{fps:g}",
                        "--beats", f"{S}/{bf}", "--metrics", m])

    if not args.no_group:
        (ps, gs), ms = timed(lambda: (load_dir(f"{S}/group/pred"), load_dir(f"{S}/group/gt")))
        out["python_load_ms"]["group"] = ms
        run_section("group", group_groups(ps, gs),
                    lambda m: ["--pred", f"{S}/group/pred", "--gt", f"{S}/group/gt", "--fps", "30",
                               "--metrics", m])
        (df, dl, gf, gl), ms = timed(lambda: (load_dir(f"{S}/duet/pred_follower"), load_dir(f"{S}/duet/pred_leader"),
                                             load_dir(f"{S}/duet/gt_follower"), load_dir(f"{S}/duet/gt_leader")))
        out["python_load_ms"]["duet"] = ms
        run_section("duet", duet_groups(df, dl, gf, gl),
                    lambda m: ["--pred", f"{S}/duet/pred_follower", "--leader", f"{S}/duet/pred_leader",
                               "--gt", f"{S}/duet/gt_follower", "--gt-leader", f"{S}/duet/gt_leader",
                               "--fps", "30", "--metrics", m])

    print()
    print(f"{'section':<22} {'metrics':<16} {'Python ms':>10} {'Rust ms':>9} {'ratio':>8}  max rel diff (per key)")
    for section, name, py, rs, worst in table:
        ratio = f"{py / rs:.1f}x" if (rs and py) else "-"
        w = "" if worst is None else ", ".join(
            f"{k} {'n/a' if v is None else f'{v:.1e}'}" for k, v in worst.items())
        print(f"{section:<22} {name:<16} {fmt_ms(py):>10} {fmt_ms(rs):>9} {ratio:>8}  {w}")
    if args.binary:
        ts = []
        for _ in range(max(args.reps, 3)):
            t = time.perf_counter()
            subprocess.run([args.binary, "--version"], stdout=subprocess.DEVNULL, check=True)
            ts.append((time.perf_counter() - t) * 1e3)
        out["rust_process_start_ms"] = statistics.median(ts)
        print(f"Rust process start alone (dancegen --version, median): {statistics.median(ts):.1f} ms "
              f"(included in every Rust time above, as is reading the .npy files)")
    print(f"Python load (excluded above): " + ", ".join(f"{k} {v:.0f} ms" for k, v in out["python_load_ms"].items()))
    if args.out:
        with open(args.out, "w") as f:
            json.dump(out, f, indent=1, default=lambda o: None if isinstance(o, float) and not math.isfinite(o) else o)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
