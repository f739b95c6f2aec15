#!/usr/bin/env python3
"""Generates configs/worlds/workspace_map.pgm: the demo's cleaning workspace, about 10 m x 32 m at
5 cm per cell, modelled on the paper's experiment (section 5.1): an outer wall, furniture fixed
to the walls (not isolated) and four bands of isolated obstacles (pillars, tables, a round
planter) so that the section splitter makes four sections.

Usage: tools/make_workspace.py [--halls N] [OUT.pgm]   (default: configs/worlds/workspace_map.pgm)
--halls 2 stacks two copies of the workspace's furniture and bands into one 10 m x 64 m hall
(configs/worlds/long_hall_map.pgm: eight sections, the 8-robot fleet's world, docs/distribution.md).
The map frame has x along the 10 m side and y along the 32 m side; the inner face of the outer
wall is at x = 0, x = 10, y = 0, y = 32. The image has a 0.25 m margin of unknown cells.
"""
import os
import sys

RES = 0.05
MARGIN = 0.25          # unknown border around the building, metres
WALL = 0.15            # wall thickness, metres
args = sys.argv[1:]
HALLS = 1
if args[:1] == ["--halls"]:
    HALLS = int(args[1])
    args = args[2:]
W_M, H_M = 10.0, 32.0 * HALLS  # inner size
FREE, OCC, UNKNOWN = 254, 0, 205

cols = round((W_M + 2 * (WALL + MARGIN)) / RES)
rows = round((H_M + 2 * (WALL + MARGIN)) / RES)
# map frame of cell (0, 0)'s lower-left corner
ORIGIN_X = -(WALL + MARGIN)
ORIGIN_Y = -(WALL + MARGIN)
grid = [[UNKNOWN] * cols for _ in range(rows)]  # grid[y][x], y = 0 at the bottom


def cell(x_m, y_m):
    return int(round((x_m - ORIGIN_X) / RES)), int(round((y_m - ORIGIN_Y) / RES))


def rect_at(x0, y0, x1, y1, v):
    cx0, cy0 = cell(x0, y0)
    cx1, cy1 = cell(x1, y1)
    for y in range(max(cy0, 0), min(cy1, rows)):
        for x in range(max(cx0, 0), min(cx1, cols)):
            grid[y][x] = v


def disc_at(xc, yc, r, v):
    cx0, cy0 = cell(xc - r, yc - r)
    cx1, cy1 = cell(xc + r, yc + r)
    for y in range(cy0, cy1 + 1):
        for x in range(cx0, cx1 + 1):
            px = ORIGIN_X + (x + 0.5) * RES
            py = ORIGIN_Y + (y + 0.5) * RES
            if (px - xc) ** 2 + (py - yc) ** 2 <= r * r:
                grid[y][x] = v


# building: wall ring, free inside
rect_at(-WALL, -WALL, W_M + WALL, H_M + WALL, OCC)
rect_at(0.0, 0.0, W_M, H_M, FREE)
for k in range(HALLS):
    dy = 32.0 * k  # each copy 32 m above the last, every other one mirrored (x -> 10 - x) so that
    mirror = k % 2 == 1  # no two copies look alike to a global localization

    def rect(x0, y0, x1, y1, v, mirror=mirror):
        rect_at(W_M - x1 if mirror else x0, y0, W_M - x0 if mirror else x1, y1, v)

    def disc(xc, yc, r, v, mirror=mirror):
        disc_at(W_M - xc if mirror else xc, yc, r, v)

    # furniture against the walls: connected to the outer wall, so not isolated obstacles
    rect(0.0, 7.0 + dy, 0.6, 9.0 + dy, OCC)      # cabinet on the left wall
    rect(9.4, 15.0 + dy, 10.0, 17.5 + dy, OCC)   # shelf on the right wall
    if k == HALLS - 1:
        rect(3.0, 31.4 + dy, 6.0, 32.0 + dy, OCC)    # counter on the top wall
    # band 1 (y 3.0 .. 5.0): two pillars and a table
    rect(2.5, 3.0 + dy, 2.9, 3.4 + dy, OCC)
    rect(7.0, 3.0 + dy, 7.4, 3.4 + dy, OCC)
    rect(4.2, 4.2 + dy, 5.6, 5.0 + dy, OCC)
    # band 2 (y 10.5 .. 13.0): a long table and a pillar
    rect(3.0, 11.0 + dy, 6.5, 12.0 + dy, OCC)
    rect(8.0, 10.5 + dy, 8.4, 10.9 + dy, OCC)
    disc(1.8, 12.6 + dy, 0.35, OCC)
    # band 3 (y 18.5 .. 21.0): a round planter and two pillars
    disc(5.0, 19.7 + dy, 0.6, OCC)
    rect(2.0, 18.5 + dy, 2.4, 18.9 + dy, OCC)
    rect(7.8, 20.6 + dy, 8.2, 21.0 + dy, OCC)
    # band 4 (y 26.0 .. 28.5): two tables
    rect(2.0, 26.0 + dy, 4.0, 27.0 + dy, OCC)
    rect(6.0, 27.5 + dy, 8.0, 28.5 + dy, OCC)

out = args[0] if args else os.path.join(os.path.dirname(__file__), "..", "configs", "worlds",
                                                         "workspace_map.pgm")
with open(out, "wb") as f:
    f.write(b"P5\n# tripodal demo workspace, made by tools/make_workspace.py\n")
    f.write(f"{cols} {rows}\n255\n".encode())
    for y in reversed(range(rows)):  # image row 0 is the top (the highest y)
        f.write(bytes(grid[y]))
print(f"{out}: {cols} x {rows} cells, origin ({ORIGIN_X:.2f}, {ORIGIN_Y:.2f})")
