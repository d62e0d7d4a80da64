"""Engine variants with one component of the plain step done twice (in-situ cost)."""
import shutil, sys, os
SRC = "/tmp/hR_old/bearing_sim_ros"
base = open(SRC + "/physics/skidding.py").read()
I = " " * 28
V = {
 "base": [],
 "wfac": [(I + "_w_factor(ball_y, ball_aux, p, hg, ws0, wsp, wcage)\n",
           I + "_w_factor(ball_y, ball_aux, p, hg, ws0, wsp, wcage)\n" + I + "_w_factor(ball_y, ball_aux, p, hg, ws0, wsp, wcage)\n")],
 "forc": [(I + "_forcing_increment(ball_y, xbl, ball_aux, p, ws0, hb, ytmp)\n",
           I + "_forcing_increment(ball_y, xbl, ball_aux, p, ws0, hb, ytmp)\n" + I + "_forcing_increment(ball_y, xbl, ball_aux, p, ws0, hb, ytmp)\n")],
 "wapp": [(I + "_w_apply(p, hg, wsp, wcage, rtmp, kst[0])\n",
           I + "_w_apply(p, hg, wsp, wcage, rtmp, kst[0])\n" + I + "_w_apply(p, hg, wsp, wcage, rtmp, kst[0])\n")],
 "film": [(" " * 24 + "_film_update(ynext, ws, p, fn, auxs, True)\n",
           " " * 24 + "_film_update(ynext, ws, p, fn, auxs, True)\n" + " " * 24 + "_copy2(filmc, fn)\n" + " " * 24 + "_film_update(ynext, ws, p, filmc, auxs, True)\n")],
 "rhs": [(" " * 24 + "_rhs(ynext, fnext, ws, ang, fx, fyy, p, dtab, wti, wto, fn, an, dn, scr, frc)\n",
          (" " * 24 + "_rhs(ynext, fnext, ws, ang, fx, fyy, p, dtab, wti, wto, fn, an, dn, scr, frc)\n") * 2)],
 "event": [(" " * 20 + "event = _step_event(a0, an, nb, has_def)\n",
            " " * 20 + "event = _step_event(a0, an, nb, has_def)\n" + " " * 20 + "if _step_event(a0, auxs, nb, has_def) == 7:\n" + " " * 24 + "event = 7\n")],
 "pred": [(" " * 24 + "for c in range(4):\n" + " " * 28 + "uv = uc[c]\n" + " " * 28 + "for r in range(10):\n" + " " * 32 + "xpred[r] += gz[c, r] * uv\n",
            " " * 24 + "for c in range(4):\n" + " " * 28 + "uv = uc[c]\n" + " " * 28 + "for r in range(10):\n" + " " * 32 + "xpred[r] += gz[c, r] * uv\n"
          + " " * 24 + "for r in range(10):\n" + " " * 28 + "xbl[r] = 0.0\n"
          + " " * 24 + "for c in range(10):\n" + " " * 28 + "yv = yc[c]\n" + " " * 28 + "for r in range(10):\n" + " " * 32 + "xbl[r] += ph[c, r] * yv\n"
          + " " * 24 + "for c in range(4):\n" + " " * 28 + "uv = uc[c]\n" + " " * 28 + "for r in range(10):\n" + " " * 32 + "xbl[r] += gz[c, r] * uv\n")],
 "diag": [(" " * 8 + "_record_diag(i, m, y, dgp[cur], ws, p, out_qi, out_qo, out_cage, out_bs, out_cs, out_sli, out_slo,\n" + " " * 21 + "out_fi, out_fo)\n",
           (" " * 8 + "_record_diag(i, m, y, dgp[cur], ws, p, out_qi, out_qo, out_cage, out_bs, out_cs, out_sli, out_slo,\n" + " " * 21 + "out_fi, out_fo)\n") * 2)],
}
for name, reps in V.items():
    if sys.argv[1:] and name not in sys.argv[1:]:
        continue
    s = base
    for a, b in reps:
        assert s.count(a) == 1, (name, s.count(a))
        s = s.replace(a, b)
    d = f"/tmp/hR_var/{name}/bearing_sim_ros"
    if os.path.exists(d):
        shutil.rmtree(d)
    shutil.copytree(SRC, d)
    open(d + "/physics/skidding.py", "w").write(s)
    print(name)
