"""Prototype: does the height above a quadric fitted at large scales separate free-form
feature bands better than the 48 BoundED features? Trains a gradient-boosted classifier
with and without the quadric columns on training clouds, scores MCC on validation clouds.

Usage: python3 freeform_quadric.py TRAIN_DIR VAL_DIR [noq] (noq: the 48 features only)
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

def quadric(xyz, scales=(128, 64, 32)):
    tree = cKDTree(xyz)
    _, idx = tree.query(xyz, k=max(scales))
    out = []
    for k in scales:
        nb = xyz[idx[:, :k]] - xyz[:, None, :]          # (n,k,3), query at origin
        c = nb.mean(1, keepdims=True)
        cov = np.einsum('nki,nkj->nij', nb - c, nb - c) / k
        w, v = np.linalg.eigh(cov)                      # ascending
        frame = v                                        # columns: normal first
        loc = np.einsum('nki,nij->nkj', nb, frame)     # (n,k,3): z along normal = col 0
        z, x, y = loc[..., 0], loc[..., 1], loc[..., 2]
        scale = np.sqrt((x * x + y * y).mean(1))[:, None] + 1e-12
        x, y, z = x / scale, y / scale, z / scale
        A = np.stack([x * x, x * y, y * y, x, y, np.ones_like(x)], -1)
        ata = np.einsum('nki,nkj->nij', A, A) + 1e-9 * np.eye(6)
        atz = np.einsum('nki,nk->ni', A, z)
        coef = np.linalg.solve(ata, atz[..., None])[..., 0]
        res = z - np.einsum('nki,ni->nk', A, coef)
        # height of the query (origin) above the quadric, sign-free with the frame's sign
        h = -coef[:, 5]
        # orient sign by curvature: make the quadric's mean curvature positive
        s = np.sign(coef[:, 0] + coef[:, 2] + 1e-12)
        rms = np.sqrt((res ** 2).mean(1))
        near = res[:, :16].mean(1)
        out += [h * s, np.abs(h), rms, near * s]
    return np.stack(out, 1)

def dataset(d, limit=None):
    X, Q, Y = [], [], []
    for p in sorted(glob.glob(d + '/*.f32'))[:limit]:
        xyz, y, f = load(p)
        X.append(f); Q.append(quadric(xyz)); Y.append(y)
    return X, Q, Y

Q_ON = len(sys.argv) < 4
if not Q_ON: quadric = lambda xyz: np.zeros((len(xyz), 0))
tr = dataset(sys.argv[1]); va = dataset(sys.argv[2])
def stack(parts, with_q):
    X, Q, Y = parts
    return np.concatenate([np.hstack([x, q]) if with_q else x for x, q in zip(X, Q)]), np.concatenate(Y)
for with_q in ((False, True) if len(sys.argv) < 4 else (False,)):
    Xt, Yt = stack(tr, with_q)
    clf = HistGradientBoostingClassifier(max_iter=300, learning_rate=0.1, random_state=0)
    clf.fit(Xt, Yt)
    m_arg, m_best, aucs = [], [], []
    for x, q, y in zip(*va):
        xx = np.hstack([x, q]) if with_q else x
        p = clf.predict_proba(xx)
        ps = p[:, list(clf.classes_).index(1)]
        t = (y == 1)
        if t.sum() == 0 or t.all():
            continue
        pred = clf.classes_[p.argmax(1)] == 1
        m_arg.append(matthews_corrcoef(t, pred))
        m_best.append(max(matthews_corrcoef(t, ps > th) for th in np.arange(0.05, 0.96, 0.05)))
        aucs.append(roc_auc_score(t, ps))
    print(f"quadric={with_q}: AUC {np.median(aucs):.3f}  MCC argmax {np.median(m_arg):.3f}  best {np.median(m_best):.3f}  (n={len(aucs)})", flush=True)
