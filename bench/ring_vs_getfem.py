#!/usr/bin/env python3
"""The paper's two-ring impact in emdae and in GetFEM, timed side by side (issue 14).

Both programs integrate the same problem, read from one scene file
(examples/ring_impact.toml unless --scene says otherwise):

  - geometry and mesh: the scene's rings, node for node (ring_mesh's nodes,
    `around` x `through` bilinear quads, plane strain);
  - material: St. Venant-Kirchhoff (or compressible Neo-Hooke, as the scene
    says) with the scene's E, nu, rho; consistent mass; 2 x 2 Gauss points;
  - step dt and span [0, t_end]; initial velocities; no loads;
  - Newton: the scene's tolerance and iteration limit (see "Newton" below);
  - frictionless contact of the slave ring's outer surface on the master's.

and the runs are interleaved, A B A B (--pairs), so that both see the same
load of a shared machine. Times are CPU seconds of the time loop only (emdae:
summary.json's cpu_seconds, which includes its per-step recording of energies
and momenta; GetFEM: process CPU time around its steps, which counts every
thread it may use, without the energy evaluation for the table), divided by
the number of time steps of size dt in [0, t_end]. Setting up the model and
writing reports are outside both.

GetFEM's side (python3-getfem, 5.4 in Debian bookworm):
  - the momentum balance of the implicit midpoint rule (--getfem-scheme
    midpoint: stress at F_mid = (F_n + F_n+1)/2) or of the energy-conserving
    rule for St. Venant-Kirchhoff (--getfem-scheme em: the stress of the
    averaged Green strain (E_n + E_n+1)/2, pushed by F_mid; Simo & Tarnow;
    for SVK this is exactly emdae's discrete gradient of the elastic part),
    written in GetFEM's weak-form language (GWFL) over the unknown
    displacement u_n+1 with u_n, v_n as data:
        2 rho/dt^2 (u_n+1 - u_n - dt v_n) . du + P_alg : Grad du + contact = 0,
        v_n+1 = 2 (u_n+1 - u_n)/dt - v_n;
  - contact: GetFEM's large sliding contact brick with ray tracing
    (add_integral_large_sliding_contact_brick_raytracing; Alart-Curnier
    augmented Lagrangian, a vector multiplier on the slave boundary,
    integrated by 3 Gauss points per slave edge, frictionless), enforced at
    t_n+1 and acting with its force at t_n+1.
What differs from emdae's em, which the table's energy column shows: emdae's
contact constraint is the mortar weighted gap in invariants (the paper's
section 4) whose discrete gradient conserves energy, and a step in which a node
enters contact is split at the instant its gap closes; GetFEM's contact force
is not a discrete gradient and its steps are not split, so the impact does
work. GetFEM's Newton stops on the 1-norm of its residual (force units),
which is given emdae's tolerance (a length: emdae scales row i by
dt^2/(2 m_i)) times 2 rho A/dt^2, A the mean nodal area of the mesh; the
1-norm over all rows makes that at least as strict as emdae's max-norm.

  bench/ring_vs_getfem.py [--emdae build/release/cli/emdae] [--scene FILE]
                          [--t-end T] [--pairs 2] [--getfem-scheme em,midpoint]
                          [--markdown FILE] [--emdae-impact velocity_update]
                          [--emdae-repeats R]

--emdae-impact adds emdae runs with other impact treatments ([scheme] impact)
beside the scene's own: velocity_update enters a closing node for the whole
step and corrects its velocity afterwards (no sub-steps, as GetFEM's
contact), with energy and momenta still exact.

Where GetFEM is not installed (python3-getfem is not importable by this
Python or by /usr/bin/python3), the script says "GetFEM not installed: only
emdae timed" and times emdae alone.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SYSTEM_PYTHON = "/usr/bin/python3"  # Debian's python3-getfem installs for it


def import_getfem():
    """getfem, or None. A Python without it (a virtualenv, pyenv) hands the run
    over to Debian's /usr/bin/python3 when that one has it."""
    try:
        import getfem  # noqa: F401

        return getfem
    except ImportError:
        pass
    if (os.path.realpath(sys.executable) != os.path.realpath(SYSTEM_PYTHON)
            and os.path.exists(SYSTEM_PYTHON)
            and not os.environ.get("RING_VS_GETFEM_REEXEC")
            and subprocess.run([SYSTEM_PYTHON, "-c", "import getfem"],
                               capture_output=True).returncode == 0):
        env = dict(os.environ, RING_VS_GETFEM_REEXEC="1")
        os.execve(SYSTEM_PYTHON, [SYSTEM_PYTHON, os.path.abspath(__file__)] + sys.argv[1:], env)
    return None


def load_toml(path):
    try:
        import tomllib
    except ImportError:  # Python < 3.11
        import tomli as tomllib
    with open(path, "rb") as f:
        return tomllib.load(f)


# --- the scene, as both programs see it ----------------------------------------------------

class Ring:
    def __init__(self, body):
        mesh = body["mesh"]
        if mesh.get("type") != "ring":
            raise SystemExit(f"body '{body['name']}': only ring meshes are compared here")
        self.name = body["name"]
        self.centre = [float(c) for c in mesh["centre"]]
        self.r_in, self.r_out = float(mesh["inner_radius"]), float(mesh["outer_radius"])
        self.around, self.through = int(mesh["around"]), int(mesh["through"])
        self.velocity = [float(c) for c in body.get("velocity", [0.0, 0.0])]
        mat = body["material"]
        self.model = mat.get("model", "svk")
        self.young, self.poisson, self.rho = (float(mat["young"]), float(mat["poisson"]),
                                              float(mat["density"]))

    def nodes(self):
        """core/mesh.cpp ring_mesh: layer j (inner to outer), angle i."""
        pts = []
        for j in range(self.through + 1):
            r = self.r_in + (self.r_out - self.r_in) * j / self.through
            for i in range(self.around):
                th = 2.0 * math.pi * i / self.around
                pts.append((self.centre[0] + r * math.cos(th), self.centre[1] + r * math.sin(th)))
        return pts

    def quads(self):
        """Counter-clockwise, as ring_mesh numbers them."""
        node = lambda j, i: j * self.around + i % self.around
        return [(node(j, i), node(j + 1, i), node(j + 1, i + 1), node(j, i + 1))
                for j in range(self.through) for i in range(self.around)]

    def area(self):
        return math.pi * (self.r_out ** 2 - self.r_in ** 2)


class Scene:
    def __init__(self, path, t_end):
        s = load_toml(path)
        self.path = path
        self.dt = float(s["time"]["dt"])
        self.t_end = float(t_end if t_end is not None else s["time"]["t_end"])
        scheme = s.get("scheme", {})
        self.tolerance = float(scheme.get("newton_tolerance", 1e-10))
        self.max_iterations = int(scheme.get("newton_max_iterations", 20))
        self.rings = {b["name"]: Ring(b) for b in s["bodies"]}
        if len(s.get("contacts", [])) != 1:
            raise SystemExit("the comparison takes one contact pair")
        c = s["contacts"][0]
        self.slave, self.master = (c["slave"].split(".")[0], c["master"].split(".")[0])
        for side in (c["slave"], c["master"]):
            if side.split(".")[1] != "outer":
                raise SystemExit("the comparison takes contact of the rings' outer surfaces")
        models = {r.model for r in self.rings.values()}
        mats = {(r.young, r.poisson, r.rho) for r in self.rings.values()}
        if len(models) != 1 or len(mats) != 1:
            raise SystemExit("the comparison takes one material for both rings")
        self.material = models.pop()
        self.young, self.poisson, self.rho = mats.pop()

    def steps(self):
        return int(round(self.t_end / self.dt))


# --- emdae ---------------------------------------------------------------------------------

def run_emdae(emdae, scene, out, impact=None):
    args = [emdae, "run", scene.path, "--out", out, "--quiet", "--t-end", repr(scene.t_end),
            "--set", "output.vtu_every=0", "--set", "output.animation_frames=0"]
    if impact:
        args += ["--set", f"scheme.impact={impact}"]
    res = subprocess.run(args, capture_output=True, text=True)
    if res.returncode not in (0, 4):  # 4: a tolerance of the scene was exceeded
        raise SystemExit(f"emdae failed ({res.returncode}): {res.stderr.strip()[-400:]}")
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    return {"cpu": s["cpu_seconds"], "energy": s["energy_rel_error_max"],
            "iterations": s.get("newton_iterations"), "steps_taken": s["steps"],
            "failures": 0}


# --- GetFEM --------------------------------------------------------------------------------

def plane_strain_lame(young, nu):
    return young * nu / ((1 + nu) * (1 - 2 * nu)), young / (2 * (1 + nu))


class GetfemRings:
    """The scene's rings in GetFEM: one mesh, one displacement field, the
    large sliding contact brick between the slave's and the master's outer
    boundary."""

    SLAVE, MASTER = 1, 2

    def __init__(self, gf, np, scene, scheme):
        self.gf, self.np, self.scene = gf, np, scene
        gf.util_trace_level(0)  # no "Global generic assembly RHS" per iteration
        gf.util_warning_level(0)
        if scene.material not in ("svk",):
            raise SystemExit("GetFEM side: only St. Venant-Kirchhoff is written here "
                             f"(the scene says '{scene.material}')")
        m = gf.Mesh("empty", 2)
        gt = gf.GeoTrans("GT_QK(2,1)")
        for ring in scene.rings.values():
            x = ring.nodes()
            for a, b, c, d in ring.quads():
                # GetFEM's QK numbering is tensor order: (0,0) (1,0) (0,1) (1,1).
                m.add_convex(gt, np.array([x[a], x[b], x[d], x[c]]).T)
        self.mesh = m
        # The outer boundary of each ring: outer faces whose points all lie on
        # its outer radius.
        faces = m.outer_faces()
        for region, name in ((self.SLAVE, scene.slave), (self.MASTER, scene.master)):
            ring = scene.rings[name]
            keep = []
            for k in range(faces.shape[1]):
                pts = m.pts(m.pid_in_faces(faces[:, k:k + 1]))
                r = np.hypot(pts[0] - ring.centre[0], pts[1] - ring.centre[1])
                if np.all(np.abs(r - ring.r_out) < 1e-8 * ring.r_out):
                    keep.append(k)
            if len(keep) != ring.around:
                raise SystemExit(f"GetFEM side: found {len(keep)} outer faces of '{name}', "
                                 f"expected {ring.around}")
            m.set_region(region, faces[:, keep])

        mf = gf.MeshFem(m, 2)
        mf.set_fem(gf.Fem("FEM_QK(2,1)"))
        self.mf = mf
        mim = gf.MeshIm(m, gf.Integ("IM_GAUSS_PARALLELEPIPED(2,3)"))  # 2 x 2 points
        assert list(gf.Integ("IM_GAUSS_PARALLELEPIPED(2,3)").nbpts()) == [4, 2, 2, 2, 2]
        self.mim = mim
        mim_c = gf.MeshIm(m, gf.Integ("IM_GAUSS_PARALLELEPIPED(2,5)"))  # 3 per edge
        mf_l = gf.MeshFem(m, 2)
        mf_l.set_fem(gf.Fem("FEM_QK(2,1)"))

        lam, mu = plane_strain_lame(scene.young, scene.poisson)
        dt = scene.dt
        md = gf.Model("real")
        md.add_fem_variable("u", mf)
        md.add_fem_data("u0", mf)
        md.add_fem_data("v0", mf)
        md.add_initialized_data("lam", [lam])
        md.add_initialized_data("mu", [mu])
        md.add_initialized_data("rho", [scene.rho])
        md.add_initialized_data("dt", [dt])
        md.add_macro("F1", "Id(2)+Grad_u")
        md.add_macro("F0", "Id(2)+Grad_u0")
        md.add_macro("Fm", "(F0+F1)/2")
        md.add_macro("E1", "(F1'*F1-Id(2))/2")
        if scheme == "em":
            # Average of the Green strains: the SVK energy's exact discrete gradient.
            md.add_macro("Ea", "((F0'*F0+F1'*F1)/2-Id(2))/2")
        elif scheme == "midpoint":
            md.add_macro("Ea", "(Fm'*Fm-Id(2))/2")
        else:
            raise SystemExit(f"unknown GetFEM scheme '{scheme}' (em or midpoint)")
        md.add_macro("Sa", "lam*Trace(Ea)*Id(2)+2*mu*Ea")
        md.add_nonlinear_term(
            mim, "(2*rho/sqr(dt))*(u-u0-dt*v0).Test_u + (Fm*Sa):Grad_Test_u")

        # Augmentation parameter of the order of E/h (h the slave edge length).
        slave = scene.rings[scene.slave]
        h = 2 * math.pi * slave.r_out / slave.around
        md.add_initialized_data("r_aug", [scene.young / h])
        md.add_filtered_fem_variable("lambda_c", mf_l, self.SLAVE)
        # Release distance: a fraction of the wall (3) and more than a step's
        # approach (closing speed 20 x dt = 0.2).
        release = 0.5 * min(r.r_out - r.r_in for r in scene.rings.values())
        ib = md.add_integral_large_sliding_contact_brick_raytracing("r_aug", release)
        md.add_master_contact_boundary_to_large_sliding_contact_brick(ib, mim_c, self.MASTER, "u")
        md.add_slave_contact_boundary_to_large_sliding_contact_brick(
            ib, mim_c, self.SLAVE, "u", "lambda_c")
        self.md = md
        # GetFEM frees an object when its Python handle goes: keep them all.
        self.keep = (gt, mim_c, mf_l)

        # Initial velocities, per ring: the dofs' basic nodes tell which ring.
        nodes = mf.basic_dof_nodes()
        v = np.zeros(mf.nbdof())
        for ring in scene.rings.values():
            d = np.hypot(nodes[0] - ring.centre[0], nodes[1] - ring.centre[1])
            on = (d > ring.r_in - 1e-6) & (d < ring.r_out + 1e-6)
            comp = np.arange(mf.nbdof()) % 2
            v[on & (comp == 0)] = ring.velocity[0]
            v[on & (comp == 1)] = ring.velocity[1]
        self.v_init = v
        self.mass = gf.asm_mass_matrix(mim, mf)
        self.node_area = sum(r.area() for r in scene.rings.values()) / (mf.nbdof() / 2)

    def energy(self, v):
        """H = 1/2 v.M v + W(u) with u the model's current displacement."""
        kinetic = 0.5 * self.scene.rho * float(self.np.dot(v, self.mass.mult(v)))
        strain = self.gf.asm_generic(self.mim, 0, "lam/2*sqr(Trace(E1))+mu*(E1:E1)", -1, self.md)
        return kinetic + float(strain)

    def run(self):
        np, md, sc = self.np, self.md, self.scene
        dt = sc.dt
        # emdae's tolerance is a length; GetFEM's residual is a force (per
        # unit thickness): the mass term's row of a node is 2 rho A/dt^2 times
        # the length.
        max_res = sc.tolerance * 2 * sc.rho * self.node_area / dt ** 2
        u = np.zeros(self.mf.nbdof())
        v = self.v_init.copy()
        md.set_variable("u", u)
        h0 = self.energy(v)
        worst, iterations, failures = 0.0, 0, 0
        cpu = 0.0
        for n in range(sc.steps()):
            t0 = time.process_time()
            md.set_variable("u0", u)
            md.set_variable("v0", v)
            md.set_variable("u", u + dt * v)
            out = md.solve("max_res", max_res, "max_iter", sc.max_iterations)
            u1 = md.variable("u")
            v = 2.0 * (u1 - u) / dt - v
            u = u1
            cpu += time.process_time() - t0
            nit, converged = (out[0], out[1]) if len(out) > 1 else (out[0], True)
            iterations += int(nit)
            failures += 0 if converged else 1
            worst = max(worst, abs(self.energy(v) - h0) / abs(h0))
            if not math.isfinite(worst):
                failures += sc.steps() - n - 1
                break
        return {"cpu": cpu, "energy": worst, "iterations": iterations,
                "steps_taken": sc.steps(), "failures": failures}


def run_getfem(gf, np, scene, scheme):
    return GetfemRings(gf, np, scene, scheme).run()


# --- the table -----------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--emdae", default=os.path.join(ROOT, "build", "release", "cli", "emdae"))
    ap.add_argument("--scene", default=os.path.join(ROOT, "examples", "ring_impact.toml"))
    ap.add_argument("--t-end", type=float, help="end time (default: the scene's)")
    ap.add_argument("--pairs", type=int, default=2, help="A B pairs, interleaved")
    ap.add_argument("--getfem-scheme", default="em,midpoint",
                    help="GetFEM's time rule(s): em (SVK energy-conserving), midpoint")
    ap.add_argument("--markdown", help="also write the table to this file")
    ap.add_argument("--emdae-repeats", type=int, default=1,
                    help="emdae runs per pair and treatment, the pair taking their median "
                         "CPU time (emdae's runs take 1-2 s and scatter by +-30 %%, GetFEM's "
                         "a minute and +-10 %%)")
    ap.add_argument("--emdae-impact", default="",
                    help="comma list of [scheme] impact treatments to run emdae with beside the "
                         "scene's own (e.g. velocity_update: no sub-steps, as GetFEM's contact)")
    a = ap.parse_args()

    gf = import_getfem()
    np = None
    if gf is not None:
        import numpy as np  # GetFEM's arrays; emdae's side needs none

    if not os.access(a.emdae, os.X_OK):
        raise SystemExit(f"no emdae at {a.emdae}: build it (cmake --build build/release) "
                         "or pass --emdae")
    scene = Scene(a.scene, a.t_end)
    steps = scene.steps()
    schemes = a.getfem_scheme.split(",") if gf else []
    if gf is None:
        print("GetFEM not installed: only emdae timed", flush=True)
    else:
        version = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "python3-getfem"],
                                 capture_output=True, text=True).stdout or "?"
        print(f"GetFEM {version} ({os.path.dirname(gf.__file__)}), schemes "
              f"{', '.join(schemes)}", flush=True)
    print(f"scene {os.path.relpath(scene.path, ROOT)}: {steps} steps of dt = {scene.dt}, "
          f"Newton tolerance {scene.tolerance:g}, {a.pairs} interleaved pair(s)", flush=True)

    # emdae as the scene says, then with each impact treatment asked for.
    emdae_runs = [("emdae em", None)] + [(f"emdae em, impact = {i}", i)
                                         for i in a.emdae_impact.split(",") if i]
    results = {label: [] for label, _ in emdae_runs}
    for s in schemes:
        results[f"GetFEM {s}"] = []
    with tempfile.TemporaryDirectory() as tmp:
        for p in range(a.pairs):
            for k, (label, impact) in enumerate(emdae_runs):
                runs = [run_emdae(a.emdae, scene, os.path.join(tmp, f"emdae{p}_{k}_{i}"), impact)
                        for i in range(max(1, a.emdae_repeats))]
                cpus = sorted(x["cpu"] for x in runs)
                r = dict(runs[0])  # the same history every run: only the time differs
                r["cpu"] = (cpus[len(cpus) // 2] if len(cpus) % 2
                            else 0.5 * (cpus[len(cpus) // 2 - 1] + cpus[len(cpus) // 2]))
                results[label].append(r)
                each = (" (median of " + ", ".join(f"{1e3 * c / steps:.2f}" for c in cpus) + ")"
                        if len(cpus) > 1 else "")
                print(f"  pair {p + 1}: {label} {1e3 * r['cpu'] / steps:.2f} ms/step{each}, "
                      f"energy {r['energy']:.1e}", flush=True)
            for s in schemes:
                r = run_getfem(gf, np, scene, s)
                results[f"GetFEM {s}"].append(r)
                print(f"  pair {p + 1}: GetFEM {s} {1e3 * r['cpu'] / steps:.2f} ms/step, "
                      f"energy {r['energy']:.1e}, {r['iterations'] / steps:.2f} it/step, "
                      f"{r['failures']} unconverged", flush=True)

    ms = {k: [1e3 * r["cpu"] / steps for r in v] for k, v in results.items()}
    ref = min(ms["emdae em"])
    header = ("| program, scheme | CPU ms per step (each run) | best | ratio to emdae em (best) "
              "| steps solved | Newton iterations per step | CPU ms per iteration (best) "
              "| unconverged steps | max rel. energy error |")
    lines = [header, "|" + "---|" * 9]
    for k, v in results.items():
        its = v[0]["iterations"]  # deterministic: the same in every run
        its_txt = f"{its / steps:.2f}" if its else "–"
        per_it = f"{min(r['cpu'] for r in v) * 1e3 / its:.2f}" if its else "–"
        lines.append(f"| {k} | {' / '.join(f'{x:.2f}' for x in ms[k])} | {min(ms[k]):.2f} | "
                     f"{min(ms[k]) / ref:.1f} | {v[0]['steps_taken']} | {its_txt} | {per_it} | "
                     f"{v[0]['failures']} | {v[0]['energy']:.1e} |")
    # Each GetFEM run over the emdae runs of its own pair, and the median.
    if schemes:
        lines += ["", "| GetFEM over emdae, pair by pair | ratios | median |", "|---|---|---|"]
        for s in schemes:
            g = results[f"GetFEM {s}"]
            for label, _ in emdae_runs:
                ratios = sorted(x["cpu"] / y["cpu"] for x, y in zip(g, results[label]))
                each = " / ".join(f"{x['cpu'] / y['cpu']:.1f}" for x, y in zip(g, results[label]))
                mid = (ratios[len(ratios) // 2] if len(ratios) % 2
                       else 0.5 * (ratios[len(ratios) // 2 - 1] + ratios[len(ratios) // 2]))
                lines.append(f"| GetFEM {s} over {label} | {each} | {mid:.1f} |")
    print("\n".join(lines))
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
