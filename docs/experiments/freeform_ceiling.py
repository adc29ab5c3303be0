"""What the 48 BoundED features can reach on free-form feature bands, with a stronger
classifier than the embedded network: scikit-learn's gradient boosting on the features
alone, with a quadric's heights beside them (`--quadric`), and then with the context the
second stage sees (the mean and maximum of the first classifier's p_sharp over the 16, 32
and 64 nearest points, and the point's p_sharp less each mean; on the training clouds from
two folds by cloud). Median ROC AUC, MCC at argmax and best MCC over thresholds 0.05-0.95
on the validation clouds.

Usage: python3 freeform_ceiling.py TRAIN_DIR VAL_DIR [--quadric]
(directories written by bounded-nn's feature_dump example; needs numpy, scipy and
scikit-learn; see docs/model.md, 2026-12-03, third stop).
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
        out.append((f, y, nb))
    return out

def context(p, nb):
    cols = []
    for k in (16, 32, 64):
        q = p[nb[:, :k]]
        cols += [q.mean(1), q.max(1), p - q.mean(1)]
    return np.stack(cols, 1)

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

train_dir, val_dir, *flags = sys.argv[1:]
q = '--quadric' in flags
tr, va = clouds(train_dir, q), clouds(val_dir, q)
first = fit([(f, y) for f, y, _ in tr])
report("features" + (" and quadric" if q else ""), first, [(f, y) for f, y, _ in va])
half = len(tr) // 2
p_tr = [None] * len(tr)
for fold, rest in ((range(half), range(half, len(tr))), (range(half, len(tr)), range(half))):
    clf = fit([tr[i][:2] for i in fold])
    for i in rest:
        p_tr[i] = p_sharp(clf, tr[i][0])
with_context = lambda f, p, nb: np.hstack([f, context(p, nb)])
second = fit([(with_context(f, p, nb), y) for (f, y, nb), p in zip(tr, p_tr)])
report("then context", second,
       [(with_context(f, p_sharp(first, f), nb), y) for f, y, nb in va])
