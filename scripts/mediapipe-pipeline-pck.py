#!/usr/bin/env python3
"""MediaPipe's own pose pipeline (its person detector + the BlazePose "full" landmark model,
`mediapipe.solutions.pose`, static images) on the PARSE test photos 101-305, plain and through
the proxy benchmark's stylisations, scored like `sketchbody-lab eval-detector --sets`: the same
canonical joints (PARSE's mapping of `detect::joints::parse_to_canonical`, MediaPipe's of
`detect::landmark::joints::to_canonical`), PCK normalised by the longer side of the true joints'
box, a missed image scoring 0. It is the reference for what the detector model we do not run
(MediaPipe's pose detection) would give as our landmark backend's ROI (docs/benchmarks-history.md,
"MediaPipe's own pipeline on the proxy benchmark").

Usage: scripts/mediapipe-pipeline-pck.py SKETCHBODY PARSE_DIR WORK_DIR [SET ...]
  SKETCHBODY  the sketchbody-lab binary (makes the stylised copies with `stylise`, seeded by the image
              number as eval-detector does); PARSE_DIR  ../shared/data/parse;
  WORK_DIR    where the stylised copies go; SET  plain, xdog, pencil, flat (default all).
Runs in the conversion venv (scripts/mediapipe-venv.sh prints its python)."""
import csv
import os
import subprocess
import sys

import cv2
import mediapipe as mp
import numpy as np

PARSE = ['lank', 'lkne', 'lhip', 'rhip', 'rkne', 'rank', 'lwr', 'lelb', 'lsho', 'rsho', 'relb', 'rwr', 'hbot', 'htop']
FIRST, LAST = 101, 305


def truth(row):
    """Canonical joints (skeleton::joint order) from a PARSE label row, continuous px."""
    p = {k: np.array([float(row[k + '_x']), float(row[k + '_y'])]) + 0.5 for k in PARSE}
    mid = lambda a, b: (p[a] + p[b]) / 2
    return np.array([mid('htop', 'hbot'), p['hbot'], p['lsho'], p['lelb'], p['lwr'], p['rsho'], p['relb'], p['rwr'],
                     mid('lhip', 'rhip'), p['lhip'], p['lkne'], p['lank'], p['rhip'], p['rkne'], p['rank']])


def canonical(lm):
    """Canonical joints from MediaPipe's 33 landmarks (px), as detect::landmark::joints."""
    mid = lambda a, b: (lm[a] + lm[b]) / 2
    sh, mouth = mid(11, 12), mid(9, 10)
    return np.array([mid(7, 8), sh + 0.5 * (mouth - sh), lm[12], lm[14], lm[16], lm[11], lm[13], lm[15],
                     mid(23, 24), lm[24], lm[26], lm[28], lm[23], lm[25], lm[27]])


def pck(t, e, alpha):
    thr = alpha * max(np.ptp(t[:, 0]), np.ptp(t[:, 1]))
    return float(np.mean(np.linalg.norm(t - e, axis=1) <= thr))


def main():
    skb, parse_dir, work = sys.argv[1:4]
    sets = sys.argv[4:] or ['plain', 'xdog', 'pencil', 'flat']
    labels = {r['image']: r for r in csv.DictReader(open(os.path.join(parse_dir, 'labels.csv')))}
    with mp.solutions.pose.Pose(static_image_mode=True, model_complexity=1) as pose:
        for s in sets:
            r1, r2, miss = [], [], 0
            for i in range(FIRST, LAST + 1):
                name = f'im{i:04d}.jpg'
                path = os.path.join(parse_dir, 'images', name)
                if s != 'plain':
                    out = os.path.join(work, s, f'im{i:04d}.png')
                    if not os.path.exists(out):
                        os.makedirs(os.path.dirname(out), exist_ok=True)
                        subprocess.run([skb, 'stylise', '--style', s, '--seed', str(i), path, out], check=True)
                    path = out
                img = cv2.imread(path)
                h, w = img.shape[:2]
                res = pose.process(cv2.cvtColor(img, cv2.COLOR_BGR2RGB))
                if res.pose_landmarks is None:
                    miss += 1
                    r1.append(0.0)
                    r2.append(0.0)
                    continue
                e = canonical(np.array([[q.x * w, q.y * h] for q in res.pose_landmarks.landmark]))
                t = truth(labels[name])
                r1.append(pck(t, e, 0.1))
                r2.append(pck(t, e, 0.2))
            n = LAST + 1 - FIRST
            print(f'{s:8s} PCK@0.1 {np.mean(r1):.3f}  PCK@0.2 {np.mean(r2):.3f}  no pose {miss}/{n} '
                  f'({100 * miss / n:.1f} %)', flush=True)


if __name__ == '__main__':
    main()
