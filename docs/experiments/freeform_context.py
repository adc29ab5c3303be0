"""Prototype: auto-context on top of a per-point classifier for free-form band labels.
Stage 1: gradient boosting on the 48 features (out-of-fold on training clouds).
Stage 2: the 48 features plus the mean / max of stage-1 p_sharp over the 16, 32, 64 nearest.

Usage: python3 freeform_context.py TRAIN_DIR VAL_DIR
(directories written by bounded-nn's feature_dump example; needs numpy, scipy and
scikit-learn; see docs/model.md, 2026-12-03, third stop).
"""
import glob, sys, numpy as np
from scipy.spatial import cKDTree
from sklearn.ensemble import HistGradientBoostingClassifier as GB
from sklearn.metrics import matthews_corrcoef, roc_auc_score

def load(path):
    with open(path, 'rb') as f:
        rows, cols = np.frombuffer(f.read(8), '<u4')
        a = np.frombuffer(f.read(), '<f4').reshape(rows, cols)
    return a[:, :3].astype(np.float64), a[:, 3].astype(int), a[:, 4:]

def clouds(d): return [load(p) for p in sorted(glob.glob(d + '/*.f32'))]
tr, va = clouds(sys.argv[1]), clouds(sys.argv[2])
idx = lambda c: cKDTree(c[0]).query(c[0], k=64)[1]
tr_i, va_i = [idx(c) for c in tr], [idx(c) for c in va]
def ctx(p, nb):
    cols = []
    for k in (16, 32, 64):
        q = p[nb[:, :k]]
        cols += [q.mean(1), q.max(1), p - q.mean(1)]
    return np.stack(cols, 1)
fit = lambda X, y: GB(max_iter=300, random_state=0).fit(X, y)
def psharp(clf, X): return clf.predict_proba(X)[:, list(clf.classes_).index(1)]
# stage 1 out of fold (2 folds by cloud)
half = len(tr) // 2
folds = [(list(range(half)), list(range(half, len(tr)))), (list(range(half, len(tr))), list(range(half)))]
p_tr = [None] * len(tr)
for a, b in folds:
    clf = fit(np.concatenate([tr[i][2] for i in a]), np.concatenate([tr[i][1] for i in a]))
    for i in b: p_tr[i] = psharp(clf, tr[i][2])
s1 = fit(np.concatenate([c[2] for c in tr]), np.concatenate([c[1] for c in tr]))
p_va = [psharp(s1, c[2]) for c in va]
X2 = np.concatenate([np.hstack([c[2], ctx(p, nb)]) for c, p, nb in zip(tr, p_tr, tr_i)])
s2 = fit(X2, np.concatenate([c[1] for c in tr]))
for name, model, feats in (("stage 1", s1, lambda c, p, nb: c[2]), ("stage 2", s2, lambda c, p, nb: np.hstack([c[2], ctx(p, nb)]))):
    m_arg, m_best, aucs = [], [], []
    for c, p, nb in zip(va, p_va, va_i):
        t = c[1] == 1
        if t.sum() == 0 or t.all(): continue
        pr = model.predict_proba(feats(c, p, nb)); ps = pr[:, list(model.classes_).index(1)]
        m_arg.append(matthews_corrcoef(t, model.classes_[pr.argmax(1)] == 1))
        m_best.append(max(matthews_corrcoef(t, ps > th) for th in np.arange(0.05, 0.96, 0.05)))
        aucs.append(roc_auc_score(t, ps))
    print(f"{sys.argv[1]} {name}: AUC {np.median(aucs):.3f}  MCC argmax {np.median(m_arg):.3f}  best {np.median(m_best):.3f}", flush=True)
