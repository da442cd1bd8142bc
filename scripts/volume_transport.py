#!/usr/bin/env python3
"""The volume grid's transport (crates/pelage-shade/wgsl/shade/volume.wgsl, `propagate`)
against a continuum Monte Carlo random walk, in a uniform cube of 16^3 cells.

A unit isotropic source in the centre cell; the medium has optical depth `kappa` per cell
edge, single-scattering albedo `a` and mean cosine `g` (Henyey-Greenstein in the Monte
Carlo; the scheme matches the first moment, as the grid does with the fibre's phase
function). Printed: the total path length of light before it leaves the cube or dies
(the integral of the fluence over the cube, in cell edges), for the Monte Carlo and for
the six-direction scheme as the grid runs it (each direction's light spread to the four
diagonal neighbours ahead, VOLUME_SPREAD each, over a path of VOLUME_STEP_PATH cell
edges per step), without the spread (straight along the axes, one cell edge per step),
and without the in-cell rescattering of light born in a cell (`volume_born`).

Needs numpy (python3 -m pip install numpy). About two minutes on two cores.
"""
import numpy as np

rng = np.random.default_rng(1)
D = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
# shade/models/volume_common.wgsl
SPREAD = 0.20116
STEP_PATH = 1.20309


def shift(a, d):
    """a moved by the integer offset d; what leaves the cube is dropped."""
    out = np.zeros_like(a)
    n = a.shape[0]
    src = tuple(slice(max(0, -x), n - max(0, x)) for x in d)
    dst = tuple(slice(max(0, x), n - max(0, -x)) for x in d)
    out[dst] = a[src]
    return out


def arrive_at(out, spread):
    """`arrival`: per direction, 1 - 4 spread straight ahead, spread to each diagonal."""
    arrive = np.zeros_like(out)
    for k in range(6):
        d = D[k].astype(int)
        arrive[k] += (1 - 4 * spread) * shift(out[k], d)
        for j in range(3):
            if d[j] != 0:
                continue
            for sign in (1, -1):
                e = np.zeros(3, int)
                e[j] = sign
                arrive[k] += spread * shift(out[k], d + e)
    return arrive


def directions(e, f):
    """`volume_directions`: energy e and flux f as light along the six axis directions."""
    l1 = np.abs(f).sum(-1)
    c = np.where(l1 > e, e / np.maximum(l1, 1e-30), 1.0)
    return c[..., None] * np.maximum(0.0, f @ D.T) + ((e - c * l1) / 6.0)[..., None]


def scheme(n, kappa, a, g, in_cell, spread, path_per_step, steps=4000):
    """Total path of the six-direction transport."""
    keep = np.exp(-kappa * path_per_step)
    cross = (1 - keep) / kappa if kappa > 0 else path_per_step
    p = (1 - np.exp(-kappa)) / kappa if kappa > 0 else 1.0
    r = a * (1 - p) if in_cell else 0.0
    born_path = ((1 - p) / kappa if kappa > 0 else 0.5) if in_cell else 0.5

    def born(e, f):
        if not in_cell:
            return e, f, 0.5 * e
        return e * p / (1 - r), f * p / (1 - r * g), e * born_path / (1 - r)

    out = np.zeros((6, n, n, n))
    c = n // 2
    e0, _, total = born(np.array(1.0), np.zeros(3))
    out[:, c, c, c] = e0 / 6
    for _ in range(steps):
        arrive = arrive_at(out, spread)
        arrived = arrive.sum(0)
        if arrived.sum() < 1e-9:
            break
        scattered = (1 - keep) * a * arrive
        e = scattered.sum(0)
        f = np.einsum("k...,kj->...j", scattered, D) * g
        e, f, path = born(e, f)
        out = keep * arrive + np.moveaxis(directions(e, f), -1, 0)
        total += cross * arrived.sum() + path.sum()
    return total


def henyey_greenstein(g, m):
    if abs(g) < 1e-3:
        return rng.uniform(-1, 1, m)
    s = (1 - g * g) / (1 - g + 2 * g * rng.uniform(0, 1, m))
    return (1 + g * g - s * s) / (2 * g)


def monte_carlo(n, kappa, a, g, m=100000):
    """Total path of light in the continuum (weights times the albedo per scattering)."""
    c = n // 2 + 0.5
    pos = np.tile([c, c, c], (m, 1)).astype(float) + rng.uniform(-0.5, 0.5, (m, 3))
    v = rng.normal(size=(m, 3))
    v /= np.linalg.norm(v, axis=1)[:, None]
    w = np.ones(m)
    alive = np.ones(m, bool)
    total = 0.0
    for _ in range(5000):
        idx = np.nonzero(alive)[0]
        if len(idx) == 0:
            break
        pp, vv = pos[idx], v[idx]
        pos_dir = np.where(vv > 0, vv, 1)
        neg_dir = np.where(vv < 0, vv, 1)
        border = np.where(vv > 0, (n - pp) / pos_dir, np.where(vv < 0, -pp / neg_dir, 1e9)).min(1)
        flight = rng.exponential(1 / kappa, len(idx)) if kappa > 0 else np.full(len(idx), 1e9)
        step = np.minimum(flight, border)
        total += (w[idx] * step).sum()
        left = flight >= border
        alive[idx[left]] = False
        stay = idx[~left]
        pos[stay] = pp[~left] + vv[~left] * step[~left, None]
        w[stay] *= a
        old = v[stay]
        mu = henyey_greenstein(g, len(stay))
        side = rng.normal(size=old.shape)
        side -= (side * old).sum(1)[:, None] * old
        side /= np.linalg.norm(side, axis=1)[:, None]
        v[stay] = mu[:, None] * old + np.sqrt(np.maximum(0, 1 - mu * mu))[:, None] * side
        alive[stay[w[stay] < 1e-4]] = False
    return total / m


if __name__ == "__main__":
    n = 16
    cases = [(0.0, 0.0, 0.0), (0.2, 0.9, 0.0), (0.5, 0.9, 0.0), (0.5, 0.99, 0.0),
             (1.0, 0.95, 0.0), (0.5, 0.9, 0.6), (1.0, 0.95, 0.6), (2.0, 0.8, 0.3),
             (4.0, 0.9, 0.3), (2.0, 0.97, 0.5), (8.0, 0.9, 0.5)]
    print("kappa albedo g | Monte Carlo | scheme (ratio) | without the spread (ratio)"
          " | without in-cell scattering (ratio)")
    for kappa, a, g in cases:
        ref = monte_carlo(n, kappa, a, g)
        grid = scheme(n, kappa, a, g, True, SPREAD, STEP_PATH)
        axes = scheme(n, kappa, a, g, True, 0.0, 1.0)
        without = scheme(n, kappa, a, g, False, SPREAD, STEP_PATH)
        print(f"{kappa:4.1f} {a:4.2f} {g:3.1f} | {ref:8.3f} | {grid:8.3f} ({grid / ref:.3f})"
              f" | {axes:8.3f} ({axes / ref:.3f}) | {without:8.3f} ({without / ref:.3f})",
              flush=True)
