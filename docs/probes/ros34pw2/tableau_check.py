"""Plain-numpy check of the engine-form tableaus: observed orders on test problems."""
import numpy as np
from tableaus import engine_form, engine_form_exact_ros2, r_inf, stab, HW

def step(T, f, ft, J, t, y, h):
    s = T["b"].size
    W = np.eye(y.size) - T["gamma"] * h * J
    K = []
    ftv = ft(t, y)
    for i in range(s):
        yi = y + h * sum(T["a"][i, j] * K[j] for j in range(i)) if i else y.copy()
        r = f(t + T["c"][i] * h, yi) + sum(T["g"][i, j] * K[j] for j in range(i)) + T["tt"][i] * h * ftv if i else f(t, y) + T["tt"][0] * h * ftv
        K.append(np.linalg.solve(W, r))
    return y + h * sum(T["b"][i] * K[i] for i in range(s))

def run(T, f, ft, Jf, y0, tend, n):
    h = tend / n
    y = y0.copy(); t = 0.0
    for _ in range(n):
        y = step(T, f, ft, Jf(t, y), t, y, h); t += h
    return y

def orders(T, prob, ns):
    f, ft, Jf, y0, tend, exact = prob
    errs = [np.max(np.abs(run(T, f, ft, Jf, y0, tend, n) - exact)) for n in ns]
    ords = [np.log2(errs[i] / errs[i + 1]) for i in range(len(errs) - 1)]
    return errs, ords

# Prothero-Robinson y' = lam (y - phi) + phi',  phi = sin(t) + cos(2t)
phi = lambda t: np.sin(t) + np.cos(2 * t)
dphi = lambda t: np.cos(t) - 2 * np.sin(2 * t)
ddphi = lambda t: -np.sin(t) - 4 * np.cos(2 * t)
def pr(lam, jfac, exact_ft=True):
    f = lambda t, y: lam * (y - phi(t)) + dphi(t)
    ft = (lambda t, y: -lam * dphi(t) + ddphi(t)) if exact_ft else (lambda t, y: 0.0 * y)
    Jf = lambda t, y: np.array([[lam * jfac]])
    return f, ft, Jf, np.array([phi(0.0)]), 1.0, np.array([phi(1.0)])

# non-stiff nonlinear system (J = 0 and f_t = 0: the method runs as an explicit RK)
def nonstiff(J="zero"):
    def f(t, y):
        return np.array([y[1], -np.sin(y[0]) + 0.3 * np.cos(t) * y[1]])
    ft = lambda t, y: np.array([0.0, -0.3 * np.sin(t) * y[1]])
    rng = np.random.default_rng(1)
    R = rng.normal(size=(2, 2))
    if J == "zero":
        return f, (lambda t, y: 0 * y), (lambda t, y: np.zeros((2, 2))), np.array([1.0, 0.0]), 2.0, None
    return f, ft, (lambda t, y: R), np.array([1.0, 0.0]), 2.0, None

def with_ref(prob, T):
    f, ft, Jf, y0, tend, _ = prob
    # reference: RK4 with many steps
    n = 20000; h = tend / n; y = y0.copy(); t = 0.0
    for _ in range(n):
        k1 = f(t, y); k2 = f(t + h / 2, y + h / 2 * k1); k3 = f(t + h / 2, y + h / 2 * k2); k4 = f(t + h, y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4); t += h
    return f, ft, Jf, y0, tend, y

if __name__ == "__main__":
    ex = engine_form_exact_ros2(); cv = engine_form("ros2")
    print("ROS2 conversion vs integrators.ROS2: max diffs a %.1e g %.1e b %.1e c %.1e tt %.1e" % tuple(
        np.max(np.abs(ex[k] - cv[k])) for k in ("a", "g", "b", "c", "tt")))
    for name in HW:
        T = engine_form(name)
        np.set_printoptions(precision=17, linewidth=150)
        print(f"\n== {name}: gamma {T['gamma']!r}  R(inf) = {r_inf(name):.3e}  |R(-25)| = {abs(stab(name, -25.0)):.3f}  |R(25i)| = {abs(stab(name, 25j)):.3f}")
        for k in ("a", "g", "b", "c", "tt"):
            print(f"  {k} =", repr(T[k]))
        ns = [10, 20, 40, 80, 160]
        for label, prob in [("non-stiff, J = 0, f_t = 0", with_ref(nonstiff("zero"), T)),
                            ("non-stiff, J random, f_t exact", with_ref(nonstiff("rand"), T)),
                            ("PR lam=-1e6, exact J, exact f_t", pr(-1e6, 1.0)),
                            ("PR lam=-1e6, J = 0.8 lam, exact f_t", pr(-1e6, 0.8)),
                            ("PR lam=-1e6, J = 1.5 lam, exact f_t", pr(-1e6, 1.5)),
                            ("PR lam=-1e6, exact J, f_t = 0", pr(-1e6, 1.0, False)),
                            ("PR lam=-1, J = 0, f_t = 0", pr(-1.0, 0.0, False)),
                            ("PR lam=-1e2, J = 0.8 lam, exact f_t", pr(-1e2, 0.8))]:
            errs, ords = orders(T, prob, ns)
            print(f"  {label:<38} err(h=1/10..1/160) " + " ".join(f"{e:.2e}" for e in errs) + "  orders " + " ".join(f"{o:.2f}" for o in ords))
