#!/usr/bin/env python3
"""Clean-silhouette copy of a Blender validation set (scripts/make-blender-set.sh): each sketch
replaced by a 1-px outline of the true posed mesh through the truth's weak-perspective camera,
the image the fit's model of a sketch assumes. The shape fit run on the copy shows what a perfect
line drawing of the same bodies would give (docs/benchmarks.md, "Where the limit is").

Usage: clean-silhouette-set.py SRC DST FACES_OBJ
  SRC        a make-blender-set.sh folder (NNNNNN.{png,json,mesh})
  DST        the copy (written; same stems, truth and meshes copied)
  FACES_OBJ  any OBJ of the body model's topology (e.g. a run-dataset NNNNNN_rest.obj): its faces
Needs numpy and OpenCV (Debian: python3-numpy python3-opencv).
"""
import sys, os, json, glob, shutil, numpy as np, cv2
src, dst, faces_obj = sys.argv[1:4]
os.makedirs(dst, exist_ok=True)
faces = []
for l in open(faces_obj):
    if l.startswith('f '):
        idx = [int(t.split('/')[0]) - 1 for t in l.split()[1:]]
        for k in range(1, len(idx) - 1):
            faces.append([idx[0], idx[k], idx[k + 1]])
faces = np.array(faces)
for mp in sorted(glob.glob(f'{src}/*.mesh')):
    s = os.path.basename(mp)[:-5]
    j = json.load(open(f'{src}/{s}.json'))
    b = open(mp, 'rb').read(); n = int.from_bytes(b[12:16], 'little')
    posed = np.frombuffer(b[16 + 12 * n:16 + 24 * n], dtype='<f4').reshape(n, 3).astype(float)
    c = j['camera']; R = np.array(c['r'])
    p = posed @ R.T
    uv = np.stack([c['sx'] * p[:, 0] + c['t'][0], -c['sy'] * p[:, 1] + c['t'][1]], 1)
    W, H = j['width'], j['height']; ss = 4
    mask = np.zeros((H * ss, W * ss), np.uint8)
    tri = np.round(uv[faces] * ss).astype(np.int32)
    for t in tri:
        cv2.fillConvexPoly(mask, t, 255)
    mask = cv2.resize(mask, (W, H), interpolation=cv2.INTER_AREA)
    m = (mask > 127).astype(np.uint8)
    edge = cv2.dilate(m, np.ones((3, 3), np.uint8)) - m
    img = np.full((H, W), 255, np.uint8); img[edge > 0] = 0
    cv2.imwrite(f'{dst}/{s}.png', img)
    shutil.copy(mp, f'{dst}/{s}.mesh'); shutil.copy(f'{src}/{s}.json', f'{dst}/{s}.json')
print('done', dst)
