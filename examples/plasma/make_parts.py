#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Draws the example parts of examples/plasma/ as ASCII DXF (docs/PLASMA.md).

These drawings are ours, written entity by entity: a small DXF *writer* (group
code / value pairs), not a parser. Every entity carries a handle so that the CAM's
messages can name it. Run it from anywhere: it writes next to itself.

  flange.dxf   rounded plate (LWPOLYLINE with bulges), a slot (bulges), four bolt
               holes from one block inserted as a 2 x 2 INSERT array, millimetres
  bracket.dxf  an L-shaped bracket drawn as loose LINEs and ARCs in mixed directions
               (the CAM chains them), an elliptical hole, millimetres
  wave.dxf     a plate whose top edge is a cubic SPLINE, with a round hole, in INCHES
  tab.dxf      a small D-shaped tab with a hole (the job that --run simulates)
"""
import math
import os
import sys


class Dxf:
    def __init__(self, insunits):
        self.insunits = insunits
        self.entities = []
        self.blocks = []
        self.handle = 0x100

    def _h(self):
        self.handle += 1
        return "%X" % self.handle

    @staticmethod
    def _pairs(pairs):
        return "".join("%d\n%s\n" % (c, v if isinstance(v, str) else repr(float(v)) if isinstance(v, float) else str(v))
                       for c, v in pairs)

    def _add(self, pairs, block):
        (block if block is not None else self.entities).append(pairs)

    def line(self, a, b, block=None):
        self._add([(0, "LINE"), (5, self._h()), (8, "0"), (10, float(a[0])), (20, float(a[1])), (30, 0.0),
                   (11, float(b[0])), (21, float(b[1])), (31, 0.0)], block)

    def arc(self, c, r, a0, a1, block=None):  # counter-clockwise from a0 to a1, degrees
        self._add([(0, "ARC"), (5, self._h()), (8, "0"), (10, float(c[0])), (20, float(c[1])), (30, 0.0),
                   (40, float(r)), (50, float(a0)), (51, float(a1))], block)

    def circle(self, c, r, block=None):
        self._add([(0, "CIRCLE"), (5, self._h()), (8, "0"), (10, float(c[0])), (20, float(c[1])), (30, 0.0),
                   (40, float(r))], block)

    def ellipse(self, c, major, ratio, block=None):
        self._add([(0, "ELLIPSE"), (5, self._h()), (100, "AcDbEntity"), (8, "0"), (100, "AcDbEllipse"),
                   (10, float(c[0])), (20, float(c[1])), (30, 0.0), (11, float(major[0])), (21, float(major[1])),
                   (31, 0.0), (40, float(ratio)), (41, 0.0), (42, 2 * math.pi)], block)

    def lwpolyline(self, pts, closed, block=None):  # pts: (x, y, bulge)
        pairs = [(0, "LWPOLYLINE"), (5, self._h()), (100, "AcDbEntity"), (8, "0"), (100, "AcDbPolyline"),
                 (90, len(pts)), (70, 1 if closed else 0)]
        for x, y, b in pts:
            pairs += [(10, float(x)), (20, float(y))]
            if b:
                pairs.append((42, float(b)))
        self._add(pairs, block)

    def spline(self, ctrl, degree, block=None):  # clamped uniform B-spline
        n = len(ctrl)
        inner = n - degree - 1
        knots = [0.0] * (degree + 1) + [float(i) / (inner + 1) for i in range(1, inner + 1)] + [1.0] * (degree + 1)
        pairs = [(0, "SPLINE"), (5, self._h()), (100, "AcDbEntity"), (8, "0"), (100, "AcDbSpline"),
                 (70, 8), (71, degree), (72, len(knots)), (73, n), (74, 0)]
        pairs += [(40, k) for k in knots]
        for x, y in ctrl:
            pairs += [(10, float(x)), (20, float(y)), (30, 0.0)]
        self._add(pairs, block)

    def block(self, name, base=(0, 0)):
        entities = []
        self.blocks.append((name, base, entities))
        return entities

    def insert(self, name, at, cols=1, rows=1, col_sp=0.0, row_sp=0.0, angle=0.0):
        pairs = [(0, "INSERT"), (5, self._h()), (8, "0"), (2, name), (10, float(at[0])), (20, float(at[1])),
                 (30, 0.0), (50, float(angle))]
        if cols > 1 or rows > 1:
            pairs += [(70, cols), (71, rows), (44, float(col_sp)), (45, float(row_sp))]
        self.entities.append(pairs)

    def text(self):
        out = self._pairs([(0, "SECTION"), (2, "HEADER"), (9, "$ACADVER"), (1, "AC1015"),
                           (9, "$INSUNITS"), (70, self.insunits), (0, "ENDSEC")])
        out += self._pairs([(0, "SECTION"), (2, "BLOCKS")])
        for name, base, ents in self.blocks:
            out += self._pairs([(0, "BLOCK"), (5, self._h()), (8, "0"), (2, name), (70, 0),
                                (10, float(base[0])), (20, float(base[1])), (30, 0.0), (3, name)])
            for e in ents:
                out += self._pairs(e)
            out += self._pairs([(0, "ENDBLK"), (5, self._h()), (8, "0")])
        out += self._pairs([(0, "ENDSEC"), (0, "SECTION"), (2, "ENTITIES")])
        for e in self.entities:
            out += self._pairs(e)
        out += self._pairs([(0, "ENDSEC"), (0, "EOF")])
        return out


def rounded_rect(w, h, r):
    """A closed LWPOLYLINE outline, counter-clockwise, corners rounded by quarter arcs (bulge tan(90/4))."""
    b = math.tan(math.radians(90) / 4)
    return [(r, 0, 0), (w - r, 0, b), (w, r, 0), (w, h - r, b), (w - r, h, 0), (r, h, b), (0, h - r, 0), (0, r, b)]


def flange():
    d = Dxf(4)
    d.lwpolyline(rounded_rect(60, 40, 6), True)
    # a slot 16 x 6 in the middle: two straight sides and two half circles (bulge 1)
    d.lwpolyline([(22, 17, 0), (38, 17, 1), (38, 23, 0), (22, 23, 1)], True)
    bolt = d.block("BOLT")
    d.circle((0, 0), 3, block=bolt)
    d.insert("BOLT", (8, 8), cols=2, rows=2, col_sp=44, row_sp=24)
    return d


def bracket():
    d = Dxf(4)
    # an L: 50 wide, 45 high, arm 16 thick, outer corner rounded R8, inner fillet R5;
    # lines in mixed directions, as CAD programs leave them
    d.line((8, 0), (50, 0))
    d.line((50, 16), (50, 0))                       # drawn downwards
    d.line((50, 16), (21, 16))
    d.arc((21, 21), 5, 180, 270)                     # inner fillet: (16,21) -> (21,16) counter-clockwise
    d.line((16, 45), (16, 21))
    d.line((0, 45), (16, 45))
    d.line((0, 8), (0, 45))
    d.arc((8, 8), 8, 180, 270)                       # outer corner
    d.ellipse((8, 32), (0, 6), 0.5)                  # an elliptical hole, 12 x 6, upright
    d.circle((38, 8), 3.5)
    return d


def wave():
    d = Dxf(1)  # inches
    w, h = 2.0, 1.2
    d.line((0, 0), (w, 0))
    d.line((w, 0), (w, h))
    d.spline([(w, h), (1.5, 1.45), (1.0, 0.95), (0.5, 1.45), (0, h)], 3)
    d.line((0, h), (0, 0))
    d.circle((1.0, 0.5), 0.25)
    return d


def tab():
    d = Dxf(4)
    d.line((0, 0), (12, 0))
    d.arc((12, 6), 6, 270, 90)
    d.line((12, 12), (0, 12))
    d.line((0, 12), (0, 0))
    d.circle((11, 6), 2.5)
    return d


def main():
    here = os.path.dirname(os.path.abspath(sys.argv[0]))
    for name, make in (("flange", flange), ("bracket", bracket), ("wave", wave), ("tab", tab)):
        with open(os.path.join(here, name + ".dxf"), "w", newline="\n") as f:
            f.write(make().text())


if __name__ == "__main__":
    main()
