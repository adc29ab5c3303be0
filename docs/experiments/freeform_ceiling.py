"""What the 48 BoundED features can reach with a stronger classifier than the embedded
network: scikit-learn's gradient boosting on the features alone, with a quadric's heights
beside them (`--quadric`), then with the context the second stage sees (the mean and maximum
of the first classifier's p_sharp over the 16, 32 and 64 nearest points, and the point's
p_sharp less each mean; on the training clouds from two folds by cloud), and then with that
context and one of the sharp-line variants of `VARIANTS` (`--line`, `--line-geometry`,
`--line-means`, `--line-means-64`). Median ROC AUC, MCC at argmax and best MCC over
thresholds 0.05-0.95 on each validation directory.

Usage: python3 freeform_ceiling.py TRAIN_DIR VAL_DIR[,VAL_DIR...] [--quadric] [--line...]
(directories written by bounded-nn's feature_dump example; needs numpy, scipy and
scikit-learn; see docs/model.md, 2026-12-03, third stop, and 2026-12-04, third stop).
"""
import glob, sys, numpy as np
from scipy.spatial import cKDTree
from sklearn.ensemble import HistGradientBoostingClassifier
from sklearn.metrics import matthews_corrcoef, roc_auc_score

def load(path):
    with open(path, 'rb') as f:
        rows, cols = np.frombuffer(f.read(8), '<u4')
        a = np.frombuffer(f.read(), '<f4').reshape(rows, cols)
    return a[:, :3].astype(np.float64), a[:, 3].astype(int), a[:, 4:]

def quadric(xyz, nb, scales=(128, 64, 32)):
    """Per scale: the point's height above z = ax^2 + bxy + cy^2 + dx + ey + f fitted in the
    neighbourhood's covariance frame, its size, the rms residual and the 16 nearest points'
    mean residual, in units of the rms radius, signed by the quadric's curvature."""
    out = []
    for k in scales:
        q = xyz[nb[:, :k]] - xyz[:, None, :]
        c = q - q.mean(1, keepdims=True)
        _, frame = np.linalg.eigh(np.einsum('nki,nkj->nij', c, c) / k)
        loc = np.einsum('nki,nij->nkj', q, frame)
        z, x, y = loc[..., 0], loc[..., 1], loc[..., 2]
        r = np.sqrt((x * x + y * y).mean(1))[:, None] + 1e-12
        x, y, z = x / r, y / r, z / r
        A = np.stack([x * x, x * y, y * y, x, y, np.ones_like(x)], -1)
        ata = np.einsum('nki,nkj->nij', A, A) + 1e-9 * np.eye(6)
        coef = np.linalg.solve(ata, np.einsum('nki,nk->ni', A, z)[..., None])[..., 0]
        res = z - np.einsum('nki,ni->nk', A, coef)
        sign = np.sign(coef[:, 0] + coef[:, 2] + 1e-12)
        h = -coef[:, 5]
        out += [h * sign, np.abs(h), np.sqrt((res ** 2).mean(1)), res[:, :16].mean(1) * sign]
    return np.stack(out, 1)

def clouds(d, with_quadric):
    out = []
    for p in sorted(glob.glob(d + '/*.f32')):
        xyz, y, f = load(p)
        nb = cKDTree(xyz).query(xyz, k=128)[1]
        if with_quadric:
            f = np.hstack([f, quadric(xyz, nb)])
        out.append((f, y, nb, xyz))
    return out

def context(p, nb):
    cols = []
    for k in (16, 32, 64):
        q = p[nb[:, :k]]
        cols += [q.mean(1), q.max(1), p - q.mean(1)]
    return np.stack(cols, 1)

def sharp_line(p, xyz, nb, scales, geometry=True, means=True):
    """Per scale, where the neighbours the first classifier calls sharp lie as a line (the
    p_sharp-weighted principal direction of the neighbourhood). With `geometry`: the point's
    distance across that line (through the weighted centroid) and its offset along it, over
    the rms radius, and the weighted spread's linearity (l1 - l2) / l1. With `means`: the mean
    p_sharp of the quarter of the neighbours nearest the line through the point along that
    direction, of the quarter furthest from it, and their difference (a band's own points
    see the band along the line; points beside it see the surface beside it)."""
    out = []
    for k in scales:
        q = xyz[nb[:, :k]] - xyz[:, None, :]
        pk = p[nb[:, :k]]
        w = pk + 1e-6
        W = w.sum(1)
        c = np.einsum('nk,nki->ni', w, q) / W[:, None]
        d = q - c[:, None, :]
        ev, vec = np.linalg.eigh(np.einsum('nk,nki,nkj->nij', w, d, d) / W[:, None, None])
        e1 = vec[:, :, 2]
        if geometry:
            along = np.einsum('ni,ni->n', -c, e1)
            across = np.linalg.norm(-c - along[:, None] * e1, axis=1)
            r = np.sqrt((q ** 2).sum(2).mean(1)) + 1e-12
            out += [across / r, np.abs(along) / r, (ev[:, 2] - ev[:, 1]) / (ev[:, 2] + 1e-12)]
        if means:
            t = np.einsum('nki,ni->nk', q, e1)
            order = np.argsort(np.linalg.norm(q - t[..., None] * e1[:, None, :], axis=2), 1)
            near = np.take_along_axis(pk, order[:, :k // 4], 1).mean(1)
            far = np.take_along_axis(pk, order[:, -(k // 4):], 1).mean(1)
            out += [near, far, near - far]
    return np.stack(out, 1)

VARIANTS = {
    'line': dict(scales=(32, 64, 128)),
    'line-geometry': dict(scales=(32, 64, 128), means=False),
    'line-means': dict(scales=(32, 64, 128), geometry=False),
    'line-means-64': dict(scales=(64,), geometry=False),
}

def fit(parts):
    X = np.concatenate([x for x, _ in parts])
    y = np.concatenate([y for _, y in parts])
    return HistGradientBoostingClassifier(max_iter=300, random_state=0).fit(X, y)

def p_sharp(clf, X):
    return clf.predict_proba(X)[:, list(clf.classes_).index(1)]

def report(name, clf, parts):
    auc, argmax, best = [], [], []
    for X, y in parts:
        t = y == 1
        if t.all() or not t.any():
            continue
        prob = clf.predict_proba(X)
        p = prob[:, list(clf.classes_).index(1)]
        auc.append(roc_auc_score(t, p))
        argmax.append(matthews_corrcoef(t, clf.classes_[prob.argmax(1)] == 1))
        best.append(max(matthews_corrcoef(t, p > th) for th in np.arange(0.05, 0.96, 0.05)))
    print(f"{name}: AUC {np.median(auc):.3f}  MCC argmax {np.median(argmax):.3f}  "
          f"best {np.median(best):.3f}", flush=True)

train_dir, val_dirs, *flags = sys.argv[1:]
q = '--quadric' in flags
variants = [f[2:] for f in flags if f[2:] in VARIANTS]
tr = clouds(train_dir, q)
vas = [(d, clouds(d, q)) for d in val_dirs.split(',')]
first = fit([(f, y) for f, y, _, _ in tr])
half = len(tr) // 2
p_tr = [None] * len(tr)
for fold, rest in ((range(half), range(half, len(tr))), (range(half, len(tr)), range(half))):
    clf = fit([tr[i][:2] for i in fold])
    for i in rest:
        p_tr[i] = p_sharp(clf, tr[i][0])
p_vas = [[p_sharp(first, f) for f, _, _, _ in va] for _, va in vas]
with_context = lambda f, p, nb: np.hstack([f, context(p, nb)])
second = fit([(with_context(f, p, nb), y) for (f, y, nb, _), p in zip(tr, p_tr)])
stages = [("features" + (" and quadric" if q else ""), first, lambda f, p, nb, xyz: f),
          ("then context", second, lambda f, p, nb, xyz: with_context(f, p, nb))]
for v in variants:
    add = lambda f, p, nb, xyz, v=v: np.hstack([with_context(f, p, nb),
                                                sharp_line(p, xyz, nb, **VARIANTS[v])])
    fitted = fit([(add(f, p, nb, xyz), y) for (f, y, nb, xyz), p in zip(tr, p_tr)])
    stages.append(("then context and " + v, fitted, add))
for (d, va), p_va in zip(vas, p_vas):
    for name, clf, columns in stages:
        report(f"{d}: {name}", clf,
               [(columns(f, p, nb, xyz), y) for (f, y, nb, xyz), p in zip(va, p_va)])
