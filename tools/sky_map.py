#!/usr/bin/env python3
"""Writes assets/environments/sky_courtyard.exr, the equirectangular sky of
assets/scenes/sky_courtyard.toml (128 x 64, linear RGB radiance in W/(m^2 sr)).

Mapping (voxgi's and Mitsuba 3's envmap): row v looks at polar angle pi v from +Y (the top row
straight up), column u along azimuth 2 pi u with u = 0 toward -Z and u = 1/4 toward +X.
The sky: a horizon-to-zenith gradient, a soft warm glow (a Gaussian lobe of 15 degrees around
a direction 35 degrees above the horizon at u = 0.35), and a dark ground below the horizon,
blended over +-3 degrees. Smooth everywhere, so that the 128 x 64 texels resolve it.

Run with the reference venv: .venv/bin/python tools/sky_map.py
"""
import pathlib

import mitsuba as mi
import numpy as np

W, H = 128, 64
root = pathlib.Path(__file__).resolve().parent.parent
out = root / "assets" / "environments" / "sky_courtyard.exr"

u = (np.arange(W) + 0.5) / W
v = (np.arange(H) + 0.5) / H
uu, vv = np.meshgrid(u, v)
theta, phi = np.pi * vv, 2 * np.pi * uu
d = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], -1)
y = d[..., 1]

horizon = np.array([1.0, 0.95, 0.9])
zenith = np.array([0.25, 0.45, 0.9])
ground = np.array([0.12, 0.10, 0.08])
t = np.sqrt(np.clip(y, 0.0, 1.0))[..., None]
sky = horizon * (1 - t) + zenith * t

g_theta, g_phi = np.radians(90 - 35), 2 * np.pi * 0.35
g = np.array([np.sin(g_theta) * np.sin(g_phi), np.cos(g_theta), -np.sin(g_theta) * np.cos(g_phi)])
angle = np.arccos(np.clip(d @ g, -1.0, 1.0))
sigma = np.radians(15.0)
sky = sky + 4.0 * np.array([1.0, 0.85, 0.6]) * np.exp(-0.5 * (angle / sigma) ** 2)[..., None]

s = np.clip((y + np.sin(np.radians(3))) / (2 * np.sin(np.radians(3))), 0.0, 1.0)[..., None]
s = s * s * (3 - 2 * s)
rgb = (ground * (1 - s) + sky * s).astype(np.float32)

mi.set_variant("scalar_rgb")
out.parent.mkdir(parents=True, exist_ok=True)
mi.Bitmap(rgb, pixel_format=mi.Bitmap.PixelFormat.RGB).write(str(out))
print(f"wrote {out}: mean {rgb.mean(axis=(0, 1))}")
