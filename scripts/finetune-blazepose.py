#!/usr/bin/env python3
"""Fine-tunes the shipped BlazePose landmark network on drawings (issue 15; an experiment).

Subcommands:
  export-identity OUT.onnx
      The asset converted to PyTorch (onnx2torch) and exported back unchanged: checks the
      export path against our loader (`cargo run --release --example landmark_model_diff --
      OUT.onnx IMAGES...` must report ~0 px).
  drift DATA STATE.pt
      How far a trained state's outputs moved from the shipped network's on 16 crops of each
      photo kind and of the pages (mean |difference| of x, y, z, the logits, and the pose flag).
  train DATA OUT_DIR [--minutes M] [--lr LR] [--seed S] [--freeze K] [--batch B] ...
      DATA is the folder `examples/landmark_finetune_data.rs` writes (crops exactly as
      inference takes them, true joints in crop px, the shipped network's outputs on them).
      Writes OUT_DIR/model.onnx (same input and output names and order as the asset),
      OUT_DIR/state.pt and OUT_DIR/log.txt.

Loss per crop (kinds: 0 plain sketch, 1 art sketch, 2 photo, 3 filtered photo, 4 page without a
figure):
  - joints: smooth L1 (beta 4 px) on the 12 directly mapped landmarks and the head (ears'
    midpoint) and pelvis (hips' midpoint) against the true joints, px / 256, weighted by the
    joint's weight (0 far outside the crop); the second-pass alignment landmark 33 (hips'
    midpoint) against the true pelvis too;
  - distillation: every one of the 195 landmark values and the pose flag kept near the shipped
    network's output on the same crop (x, y, z / 256 smooth L1; logits / 8 smooth L1; flag as
    binary cross-entropy to the shipped flag); weight `--distill-photo` on photos and pages
    without a figure, `--distill-drawing` on drawings;
  - pose flag on drawings with a figure: binary cross-entropy to 1, weight `--flag-drawing`.
Deterministic given the seed and --steps (torch.use_deterministic_algorithms, 2 CPU threads); with
the --minutes budget the number of steps depends on the machine's speed. Defaults: the best run of
docs/benchmarks-history.md ("Fine-tuning the landmark model on drawings": run 1, 470 steps in 12 min).
"""
import argparse
import os
import sys
import time
import warnings

import numpy as np
import onnx
import onnx.numpy_helper
import onnx2torch
import torch
import torch.nn.functional as F

ASSET = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "assets", "pose_landmark_full.onnx")
OUTPUT_NAMES = ["Identity", "Identity_1", "Identity_2", "Identity_3", "Identity_4"]
META = 2 + 3 * 15 + 195 + 1
SIDE = 256
# Canonical joint -> MediaPipe landmark (joints.rs); head and pelvis are midpoints.
DIRECT = [(2, 12), (3, 14), (4, 16), (5, 11), (6, 13), (7, 15), (9, 24), (10, 26), (11, 28), (12, 23), (13, 25), (14, 27)]
HEAD, PELVIS = 0, 8


def load_net(batched=False):
    """The asset as a PyTorch module; `batched`: the segmentation output's reshape (the graph's
    only fixed batch size of 1) made batch-free for training. Export from the unbatched module
    (the state dicts are the same), the graph verified against our loader."""
    warnings.filterwarnings("ignore")
    model = onnx.load(ASSET)
    if batched:
        shapes = {n.input[1] for n in model.graph.node if n.op_type == "Reshape"}
        for init in model.graph.initializer:
            value = onnx.numpy_helper.to_array(init)
            if init.name in shapes and value[0] == 1:
                value = value.copy()
                value[0] = -1
                init.CopyFrom(onnx.numpy_helper.from_array(value, init.name))
    return onnx2torch.convert(model)


def export(net, path):
    net.eval()
    x = torch.rand(1, SIDE, SIDE, 3, generator=torch.Generator().manual_seed(0))
    kw = dict(input_names=["input_1"], output_names=OUTPUT_NAMES, opset_version=13, do_constant_folding=True)
    with torch.no_grad():
        try:
            torch.onnx.export(net, (x,), path, dynamo=False, **kw)
        except TypeError:
            torch.onnx.export(net, (x,), path, **kw)


def load_data(d):
    meta = np.fromfile(os.path.join(d, "meta.f32"), dtype="<f4").reshape(-1, META)
    crops = np.memmap(os.path.join(d, "crops.u8"), dtype=np.uint8, mode="r").reshape(-1, SIDE, SIDE, 3)
    assert len(crops) == len(meta), (len(crops), len(meta))
    return crops, meta


def predicted_joints(lm):
    """(B, 39, 5) landmarks -> (B, 15, 2) canonical joints (neck left at 0: not trained)."""
    b = lm.shape[0]
    out = lm.new_zeros(b, 15, 2)
    for j, i in DIRECT:
        out[:, j] = lm[:, i, :2]
    out[:, HEAD] = 0.5 * (lm[:, 7, :2] + lm[:, 8, :2])
    out[:, PELVIS] = 0.5 * (lm[:, 23, :2] + lm[:, 24, :2])
    return out


TRAINED = [HEAD, PELVIS] + [j for j, _ in DIRECT]


def losses(net, x, meta, args):
    outs = net(x)
    lm = outs[0].reshape(-1, 39, 5)
    flag = outs[1].reshape(-1).clamp(1e-6, 1 - 1e-6)
    kind = meta[:, 0]
    target = meta[:, 2:32].reshape(-1, 15, 2)
    weight = meta[:, 32:47]
    teacher = meta[:, 47:242].reshape(-1, 39, 5)
    tflag = meta[:, 242].clamp(1e-6, 1 - 1e-6)
    figure = kind != 4
    drawing = (kind == 0) | (kind == 1) | (kind == 3)
    # Joints.
    pj = predicted_joints(lm)
    idx = torch.tensor(TRAINED)
    err = F.smooth_l1_loss(pj[:, idx] / SIDE, target[:, idx] / SIDE, beta=4.0 / SIDE, reduction="none").sum(-1)
    w = weight[:, idx]
    align = F.smooth_l1_loss(lm[:, 33, :2] / SIDE, target[:, PELVIS] / SIDE, beta=4.0 / SIDE, reduction="none").sum(-1)
    joint_loss = ((err * w).sum(1) + align * weight[:, PELVIS]) / (w.sum(1) + weight[:, PELVIS]).clamp(min=1)
    joint_loss = (joint_loss * figure).sum() / x.shape[0]
    # Distillation.
    d_pos = F.smooth_l1_loss(lm[:, :, :3] / SIDE, teacher[:, :, :3] / SIDE, beta=4.0 / SIDE, reduction="none").sum(-1).mean(1)
    d_logit = F.smooth_l1_loss(lm[:, :, 3:] / 8, teacher[:, :, 3:] / 8, beta=0.1, reduction="none").sum(-1).mean(1)
    d_flag = F.binary_cross_entropy(flag, tflag, reduction="none") - F.binary_cross_entropy(tflag, tflag, reduction="none")
    dw = torch.where(drawing, torch.full_like(kind, args.distill_drawing), torch.full_like(kind, args.distill_photo))
    distill = (dw * (d_pos + d_logit + 0.1 * d_flag)).sum() / x.shape[0]
    # Pose flag up on drawings with a figure.
    fl = (F.binary_cross_entropy(flag, torch.ones_like(flag), reduction="none") * drawing).sum() / x.shape[0]
    total = joint_loss + distill + args.flag_drawing * fl
    return total, joint_loss.item(), distill.item(), fl.item(), pj.detach()


def n_sketch_images(meta):
    """Number of rendered-sketch source images (they come first)."""
    sk = meta[:, 0] <= 1
    return int(meta[sk, 1].max()) + 1 if sk.any() else 0


def batch(crops, meta, ids):
    x = torch.from_numpy(crops[np.sort(ids)].astype(np.float32) / 255.0)
    m = torch.from_numpy(meta[np.sort(ids)])
    return x, m


def evaluate(net, crops, meta, ids, bs=16):
    """Mean px error (256² crop) of the trained joints and mean pose flag, per kind."""
    net.eval()
    res = {}
    with torch.no_grad():
        for s in range(0, len(ids), bs):
            x, m = batch(crops, meta, ids[s:s + bs])
            outs = net(x)
            lm = outs[0].reshape(-1, 39, 5)
            pj = predicted_joints(lm)
            idx = torch.tensor(TRAINED)
            e = (pj[:, idx] - m[:, 2:32].reshape(-1, 15, 2)[:, idx]).norm(dim=-1)
            w = m[:, 32:47][:, idx]
            te = (predicted_joints(m[:, 47:242].reshape(-1, 39, 5))[:, idx] - m[:, 2:32].reshape(-1, 15, 2)[:, idx]).norm(dim=-1)
            for k in range(len(x)):
                r = res.setdefault(int(m[k, 0]), [0.0, 0.0, 0.0, 0.0, 0])
                if w[k].sum() > 0:
                    r[0] += float((e[k] * w[k]).sum() / w[k].sum())
                    r[1] += float((te[k] * w[k]).sum() / w[k].sum())
                r[2] += float(outs[1].reshape(-1)[k])
                r[3] += float(m[k, 242])
                r[4] += 1
    net.train()
    names = {0: "sketch", 1: "art", 2: "photo", 3: "filtered", 4: "negative"}
    return "; ".join(
        f"{names[k]} n {r[4]} err {r[0] / r[4]:.2f} px (shipped {r[1] / r[4]:.2f}) flag {r[2] / r[4]:.3f} (shipped {r[3] / r[4]:.3f})"
        for k, r in sorted(res.items())
    )


def drift(args):
    crops, meta = load_data(args.data)
    net = load_net(batched=True)
    net.load_state_dict(torch.load(args.state))
    net.eval()
    rng = np.random.default_rng(0)
    names = {2: "photo", 3: "filtered", 4: "pages"}
    for k, name in names.items():
        ids = rng.choice(np.nonzero(meta[:, 0] == k)[0], 16, replace=False)
        x, m = batch(crops, meta, ids)
        with torch.no_grad():
            o = net(x)
        d = (o[0].reshape(-1, 39, 5) - m[:, 47:242].reshape(-1, 39, 5)).abs().mean(dim=(0, 1))
        print(f"{name}: x {d[0]:.2f} px, y {d[1]:.2f} px, z {d[2]:.2f}, visibility logit {d[3]:.2f}, "
              f"presence logit {d[4]:.2f}; pose flag {o[1].reshape(-1).mean():.3f} (shipped {m[:, 242].mean():.3f})")


def train(args):
    torch.manual_seed(args.seed)
    np.random.seed(args.seed)
    torch.use_deterministic_algorithms(True)
    crops, meta = load_data(args.data)
    n = len(meta)
    image = meta[:, 1].astype(np.int64)
    kind = meta[:, 0].astype(np.int64)
    # Hold out a tenth of the source images (a photo with all its copies) for progress figures.
    group = np.where(kind <= 1, image, np.where(kind <= 3, 100000 + (image - n_sketch_images(meta)) // 8, image))
    held = np.isin(group % 20, [6, 7])
    train_ids, val_ids = np.nonzero(~held)[0], np.nonzero(held)[0]
    # Progress figures on at most 200 of them (every k-th), to keep evaluation cheap.
    val_ids = val_ids[:: max(1, len(val_ids) // 200)]
    # Sampling weights: share per kind.
    share = {0: args.share_sketch / 2, 1: args.share_sketch / 2, 2: args.share_photo, 3: args.share_filtered, 4: args.share_negative}
    p = np.array([share[k] / max(1, np.sum(kind[train_ids] == k)) for k in kind[train_ids]])
    p /= p.sum()
    rng = np.random.default_rng(args.seed)
    net = load_net(batched=True)
    net.train()
    params = list(net.named_parameters())
    convs = [name for name, _ in params if name.endswith("weight")]
    frozen = set(convs[: args.freeze])
    trainable = []
    for name, prm in params:
        base = name.rsplit(".", 1)[0] + ".weight"
        prm.requires_grad_(base not in frozen)
        if prm.requires_grad:
            trainable.append(prm)
    os.makedirs(args.out, exist_ok=True)
    log = open(os.path.join(args.out, "log.txt"), "w")

    def say(s):
        print(s, flush=True)
        log.write(s + "\n")
        log.flush()

    say(f"{n} crops ({len(train_ids)} train, {len(val_ids)} held out), {len(params)} tensors, {len(convs)} weights, "
        f"first {args.freeze} frozen, {sum(p.numel() for p in trainable)} trainable values; args {vars(args)}")
    say("held out before: " + evaluate(net, crops, meta, val_ids))
    if args.relative_lr:
        # One step size per layer, relative to the scale of its weights (mean |w|): Adam's steps
        # have one size for every value, and the weights' scales span 0.003 to 7.
        scale = {name.rsplit(".", 1)[0]: prm.detach().abs().mean().item() for name, prm in params if name.endswith("weight")}
        groups = [
            {"params": [prm], "lr": args.relative_lr * scale[name.rsplit(".", 1)[0]], "base": args.relative_lr * scale[name.rsplit(".", 1)[0]]}
            for name, prm in params
            if prm.requires_grad
        ]
    else:
        groups = [{"params": trainable, "lr": args.lr, "base": args.lr}]
    opt = torch.optim.Adam(groups)
    t0 = time.time()
    step = 0
    train_seconds = 0.0
    budget = args.minutes * 60
    while True:
        el = train_seconds
        if (args.steps and step >= args.steps) or (not args.steps and el > budget):
            break
        frac = step / args.steps if args.steps else el / budget
        for g in opt.param_groups:
            warm = min(1.0, (step + 1) / args.warmup) if args.warmup else 1.0
            g["lr"] = warm * g["base"] * (0.1 + 0.9 * 0.5 * (1 + np.cos(np.pi * frac)))
        ids = rng.choice(train_ids, size=args.batch, p=p)
        x, m = batch(crops, meta, ids)
        if args.augment:
            # Mild photometric jitter: contrast and brightness (white stays near white).
            a = torch.from_numpy(rng.uniform(0.85, 1.15, size=(len(x), 1, 1, 1)).astype(np.float32))
            x = (1 - (1 - x) * a).clamp(0, 1)
        ts = time.time()
        loss, lj, ld, lf, _ = losses(net, x, m, args)
        opt.zero_grad()
        loss.backward()
        opt.step()
        train_seconds += time.time() - ts
        step += 1
        if step % 20 == 0:
            say(f"step {step} {el:.0f} s lr {opt.param_groups[0]['lr']:.2e} loss {loss.item():.4f} joints {lj:.4f} distill {ld:.4f} flag {lf:.4f}")
        if args.eval_every and step % args.eval_every == 0:
            say(f"held out at step {step}: " + evaluate(net, crops, meta, val_ids))
    say(f"{step} steps of {args.batch} in {time.time() - t0:.0f} s ({train_seconds:.0f} s training)")
    say("held out after: " + evaluate(net, crops, meta, val_ids))
    torch.save(net.state_dict(), os.path.join(args.out, "state.pt"))
    single = load_net()
    single.load_state_dict(net.state_dict())
    export(single, os.path.join(args.out, "model.onnx"))
    say(f"wrote {os.path.join(args.out, 'model.onnx')}")


def main():
    torch.set_num_threads(2)
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("export-identity")
    e.add_argument("out")
    dr = sub.add_parser("drift")
    dr.add_argument("data")
    dr.add_argument("state")
    t = sub.add_parser("train")
    t.add_argument("data")
    t.add_argument("out")
    t.add_argument("--minutes", type=float, default=12, help="training time budget (when --steps is 0)")
    t.add_argument("--steps", type=int, default=0, help="a fixed number of steps instead (reproducible)")
    t.add_argument("--lr", type=float, default=3e-5)
    t.add_argument("--seed", type=int, default=81)
    t.add_argument("--batch", type=int, default=16)
    t.add_argument("--freeze", type=int, default=60, help="conv weights frozen, in graph order")
    t.add_argument("--distill-photo", type=float, default=1.0)
    t.add_argument("--distill-drawing", type=float, default=0.2)
    t.add_argument("--flag-drawing", type=float, default=0.0)
    t.add_argument("--share-sketch", type=float, default=0.35)
    t.add_argument("--share-photo", type=float, default=0.2)
    t.add_argument("--share-filtered", type=float, default=0.35)
    t.add_argument("--share-negative", type=float, default=0.1)
    t.add_argument("--augment", action="store_true")
    t.add_argument("--warmup", type=int, default=0, help="steps of linear learning-rate warm-up")
    t.add_argument("--relative-lr", type=float, default=0.0,
                   help="per-layer step size = this x the layer's mean |weight| (instead of --lr)")
    t.add_argument("--eval-every", type=int, default=0)
    a = ap.parse_args()
    if a.cmd == "export-identity":
        export(load_net(), a.out)
    elif a.cmd == "drift":
        drift(a)
    else:
        train(a)


if __name__ == "__main__":
    sys.exit(main())
