#!/usr/bin/env python3
"""Mean absolute error of the five proportion factors (legs, arms, shoulders, head, torso) of
`run-dataset` results against the ground truth's `style.proportions`, for standard (all 1) and
non-standard samples. For each results folder it prints the closed-form estimate
(`proportion_estimate`) and the fitted factors (`proportions`); a missing or null field counts
as factors 1 (the prior centre without the estimate).

Usage: scripts/proportion_errors.py DATASET RESULTS [RESULTS ...]
"""
import glob
import json
import os
import sys

NAMES = ['legs', 'arms', 'shoulders', 'head', 'torso']


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    dataset = sys.argv[1]
    for res in sys.argv[2:]:
        for key in ['proportion_estimate', 'proportions']:
            acc = {'standard': [], 'non-standard': []}
            for path in sorted(glob.glob(os.path.join(dataset, '*.json'))):
                stem = os.path.basename(path)[:-5]
                if not stem.isdigit():
                    continue
                truth = json.load(open(path))['style']['proportions']
                out = os.path.join(res, stem + '.json')
                if not os.path.exists(out):
                    continue
                got = json.load(open(out)).get(key) or {n: 1.0 for n in NAMES}
                group = 'standard' if all(abs(truth[n] - 1) < 1e-12 for n in NAMES) else 'non-standard'
                acc[group].append([abs(got[n] - truth[n]) for n in NAMES])
            for group, rows in acc.items():
                if not rows:
                    continue
                m = [sum(r[i] for r in rows) / len(rows) for i in range(5)]
                print('%s %-19s %-12s n %3d mean abs err %.4f | %s' % (
                    res, key, group, len(rows), sum(m) / 5, ' '.join('%s %.3f' % (n, x) for n, x in zip(NAMES, m))))


if __name__ == '__main__':
    main()
