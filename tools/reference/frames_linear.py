#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
"""The frame scheme linearized at rest, written apart from sim/ (numpy, h5py).

Reads a fascia model file and solves K u = f for small displacements under
its gravity: per frame a translation du and a rotation dtheta, per sample

    dF = sum_i (du_i + dtheta_i x d_is) g_is^T + w_is [dtheta_i]x,
    energy v (mu e:e + lambda_s/2 tr(e)^2), e = sym(dF),

the volumetric patches' (lambda - lambda_s)/2 V_p mean(tr e)^2 with
lambda_s = lambda mu / (lambda + mu) on a patched sample (lambda elsewhere),
the rotation smoothing's v k_c sum_c |sum_i g_ic dtheta_i|^2 (k_c as
sim/src/cpu/system.c), gravity on each sample's mass at its blended position,
fixed frames held. Prints the probes' displacements, one line each:
"probe NAME ux uy uz". For the stiff cantilever (E = 4 MPa) this is
fascia's static answer to within its geometric nonlinearity (tests/t363).

--enhanced-modes adds, per volumetric patch, the nine incompatible modes
dF_s += a_c (x) e_c (X_s - X_p)_c (c = x, y, z; X_p the patch's
volume-weighted centre, so each mode averages to zero over the patch) as
unknowns of their own: a linear trial of an enrichment before it is built
(docs/mechanics.md, "Volumetric locking and volumetric patches").
--normal-modes adds only the three with r = c (dF_cc += a_c (X_s - X_p)_c),
the set fascia beam gives hexahedral cells (docs/mechanics.md, "Enhanced
strain modes").

usage: frames_linear.py MODEL.h5 [--enhanced-modes | --normal-modes]
"""
import sys

import h5py
import numpy as np

FRAME_FREE = 0


def cross_matrix(v):
    """[v]x: [v]x w = v x w, for an array of vectors (..., 3)."""
    m = np.zeros(v.shape[:-1] + (3, 3))
    m[..., 0, 1], m[..., 0, 2] = -v[..., 2], v[..., 1]
    m[..., 1, 0], m[..., 1, 2] = v[..., 2], -v[..., 0]
    m[..., 2, 0], m[..., 2, 1] = -v[..., 1], v[..., 0]
    return m


def sample_map(d, g, w):
    """B (9 x 6n): row-major dF of one sample from its n frames' (du, dtheta)."""
    n = len(w)
    B = np.zeros((3, 3, n, 6))
    for a in range(n):
        for k in range(3):
            B[k, :, a, k] = g[a]  # du_k moves row k by g
            e = np.zeros(3)
            e[k] = 1
            B[:, :, a, 3 + k] = np.outer(np.cross(e, d[a]), g[a]) + w[a] * cross_matrix(e)
    return B.reshape(9, 6 * n)


def solve(path, modes=()):
    """modes: the (r, c) entries of F that vary along X_c, one unknown each per patch."""
    f = h5py.File(path, "r")
    X = f["frames/position"][:]
    kind = f["frames/kind"][:]
    offsets = f["samples/offsets"][:]
    pair_frame, pair_weight, pair_gradient = f["pairs/frame"][:], f["pairs/weight"][:], f["pairs/gradient"][:]
    P, V = f["samples/position"][:], f["samples/volume"][:]
    patch = f["samples/patch"][:] if "samples/patch" in f else np.full(len(V), -1)  # version 1: no patches
    material = f["samples/material"][:]
    E, nu = f["materials/youngs_modulus"][:], f["materials/poisson_ratio"][:]
    rho, smoothing = f["materials/density"][:], f["materials/rotation_smoothing"][:]
    gravity = f["gravity"][:]
    N, S = len(X), len(V)
    lam_all, mu_all = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))

    patches = {p: k for k, p in enumerate(sorted(set(patch[patch >= 0].tolist())))}
    patch_volume, patch_centre = np.zeros(len(patches)), np.zeros((len(patches), 3))
    for s in np.flatnonzero(patch >= 0):
        k = patches[patch[s]]
        patch_volume[k] += V[s]
        patch_centre[k] += V[s] * P[s]
    patch_centre /= np.maximum(patch_volume, 1e-300)[:, None]
    unknowns = 6 * N + len(modes) * len(patches)

    swap = np.zeros((9, 9))  # vec(A^T) = swap vec(A)
    for r in range(3):
        for c in range(3):
            swap[3 * r + c, 3 * c + r] = 1
    identity = np.eye(3).reshape(9)
    K_all = np.zeros((unknowns, unknowns))  # dense: the beams this is for have a few thousand unknowns
    load = np.zeros(unknowns)
    patch_gradient = [dict() for _ in patches]
    patch_lambda = np.zeros(len(patches))
    for s in range(S):
        ks = np.arange(offsets[s], offsets[s + 1])
        frames, w, g = pair_frame[ks], pair_weight[ks], pair_gradient[ks]
        d = P[s] - X[frames]
        lam, mu = lam_all[material[s]], mu_all[material[s]]
        B = sample_map(d, g, w)
        dofs = (6 * frames[:, None] + np.arange(6)).ravel()
        lam_s = lam
        if patch[s] >= 0:
            k = patches[patch[s]]
            lam_s = lam * mu / (lam + mu)
            patch_lambda[k] = lam - lam_s
            for dof, value in zip(dofs, V[s] * (B.T @ identity)):
                patch_gradient[k][dof] = patch_gradient[k].get(dof, 0) + value
            if modes:
                xi = P[s] - patch_centre[k]
                columns = np.zeros((9, len(modes)))  # unknown j: dF_rc += a_j xi_c
                for j, (r, c) in enumerate(modes):
                    columns[3 * r + c, j] = xi[c]
                B = np.hstack([B, columns])
                dofs = np.concatenate([dofs, 6 * N + len(modes) * k + np.arange(len(modes))])
        D = mu * (np.eye(9) + swap) + lam_s * np.outer(identity, identity)
        K = V[s] * B.T @ D @ B
        # rotation smoothing, k_c = mu (r h)^2 with h^2 the weighted squared distance to the frames
        kc = mu * smoothing[material[s]] ** 2 * np.sum(np.abs(w) * np.sum(d * d, axis=1))
        theta = (6 * np.arange(len(ks))[:, None] + 3 + np.arange(3)).ravel()
        K[np.ix_(theta, theta)] += 2 * V[s] * kc * np.kron(g @ g.T, np.eye(3))
        K_all[np.ix_(dofs, dofs)] += K
        mass = rho[material[s]] * V[s]
        for a, i in enumerate(frames):
            load[6 * i : 6 * i + 3] += mass * w[a] * gravity
            load[6 * i + 3 : 6 * i + 6] += mass * w[a] * np.cross(d[a], gravity)
    for k, gradient in enumerate(patch_gradient):
        dofs, G = np.array(list(gradient)), np.array(list(gradient.values()))
        K_all[np.ix_(dofs, dofs)] += patch_lambda[k] / patch_volume[k] * np.outer(G, G)
    free = np.ones(unknowns, bool)
    for i in np.flatnonzero(kind != FRAME_FREE):
        free[6 * i : 6 * i + 6] = False
    u = np.zeros(unknowns)
    u[free] = np.linalg.solve(K_all[np.ix_(free, free)], load[free])

    probes = []
    names, probe_offsets = f["probes/name"][:], f["probes/offsets"][:]
    probe_frame, probe_weight, probe_position = f["probes/frame"][:], f["probes/weight"][:], f["probes/position"][:]
    for p, name in enumerate(names):
        out = np.zeros(3)
        for k in range(probe_offsets[p], probe_offsets[p + 1]):
            i = probe_frame[k]
            out += probe_weight[k] * (u[6 * i : 6 * i + 3] + np.cross(u[6 * i + 3 : 6 * i + 6], probe_position[p] - X[i]))
        probes.append((name.decode().rstrip("\0"), out))
    return probes


NINE_MODES = [(r, c) for c in range(3) for r in range(3)]
NORMAL_MODES = [(c, c) for c in range(3)]


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help") or len(argv) > 3 or \
            any(a not in ("--enhanced-modes", "--normal-modes") for a in argv[2:]):
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    modes = NINE_MODES if "--enhanced-modes" in argv[2:] else NORMAL_MODES if "--normal-modes" in argv[2:] else ()
    for name, u in solve(argv[1], modes):
        print("probe %s %.9e %.9e %.9e" % (name, u[0], u[1], u[2]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
