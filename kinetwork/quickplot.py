"""The probe plots of ``kinetwork run --plot`` as PNG files, drawn with Pillow.

matplotlib takes a second to import and more than half a second to draw the seed's eight
panels; the run itself takes milliseconds. This module draws the same figure (the layout of
``plotlayout``, which ``plot.py`` draws too: panels, titles, units, margins, 1-2-2.5-5 ticks
labelled like matplotlib's ScalarFormatter; tab10 colours, DejaVu Sans, 150 dpi, the same
pixel size) in a tenth of a second: lines at twice the size, reduced with a box filter, so
they are antialiased; texts by FreeType at the file's size, antialiased too.

It draws what the command line's plots hold: one run, scalars and x/y/z vectors, events, nan
gaps, the hide-flat note. :func:`drawable` says when a file needs matplotlib instead (another
format, an orientation's nine dashed curves, several runs, a time axis matplotlib would draw
with an offset); ``kinetwork.plot.save_plot`` stays the way for everything else.
"""

import functools
import importlib.util
import math
import os
import pathlib
import struct
import zlib

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from . import plotlayout as layout
from .errors import ModelError
from .plotlayout import EDGE, Axis, padded, time_limits
from .util import atomic_write

DPI, SCALE = 150, 2                     # the file's resolution; lines drawn this much larger
PX = DPI / 72.0                         # points -> pixels of the file
#: matplotlib's default style (rcParams), in points
FONT, SUPTITLE, SMALL = 10.0, 12.0, 6.94
LINE, SPINE, TICK, TICK_PAD, LABEL_PAD, TITLE_PAD = 1.5, 0.8, 3.5, 3.5, 4.0, 6.0
TAB10 = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
         "#7f7f7f", "#bcbd22", "#17becf"]
GRID = (223, 223, 223)                  # #b0b0b0 at alpha 0.4 on white
EVENT, NOTE = (140, 140, 140), (89, 89, 89)


def drawable(path, results, names=()):
    """Whether this module draws the plot file ``path`` of one run ``results`` as
    ``save_plot`` would: a .png whose panels are scalars or vectors, on a time axis
    matplotlib labels without an offset (a run far from t = 0 relative to its length)."""
    if os.path.splitext(str(path))[1].lower() != ".png" or isinstance(results, (list, tuple)):
        return False
    t = np.asarray(results.t, dtype=float)
    if len(t) > 1 and abs(t[0]) >= 100 * (t[-1] - t[0]):
        return False
    try:
        wanted = layout.panel_names(results, names)
    except ModelError:                  # save_plot says what is wrong with the names
        return False
    return all(np.ndim(results[name]) <= 2 for name in wanted)


def save_png(results, path, *names, title=None, hide_flat=False):
    """``save_plot(results, path, *names, title=, hide_flat=)`` for a .png that
    :func:`drawable` accepts. Raises ModelError as save_plot does (nothing to plot, an
    unknown name, only constant signals with hide_flat)."""
    image = render(results, *names, title=title, hide_flat=hide_flat)
    data = png_bytes(image)
    atomic_write(path, lambda tmp: pathlib.Path(tmp).write_bytes(data))


def png_bytes(image):
    """An RGB image as a PNG file's bytes: rows unfiltered, zlib level 1. Pillow's encoder
    tries five filters on every row, which takes twice as long for a larger file here."""
    height, width = image.height, image.width
    rows = np.zeros((height, 1 + 3 * width), dtype=np.uint8)        # filter byte 0: none
    rows[:, 1:] = np.asarray(image, dtype=np.uint8).reshape(height, 3 * width)

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + \
            struct.pack(">I", zlib.crc32(kind + body))

    per_metre = round(DPI / 0.0254)
    return b"".join([b"\x89PNG\r\n\x1a\n",
                     chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)),
                     chunk(b"pHYs", struct.pack(">IIB", per_metre, per_metre, 1)),
                     chunk(b"tEXt", b"Software\x00kinetwork"),
                     chunk(b"IDAT", zlib.compress(rows.tobytes(), 1)),
                     chunk(b"IEND", b"")])


def render(results, *names, title=None, hide_flat=False):
    """The figure as an RGB image (the file's pixels)."""
    wanted, hidden = layout.panel_names(results, names), []
    if hide_flat:
        wanted, hidden = layout.drop_flat([results], wanted)
    rows, n_cols = layout.rows(results, wanted)
    note = layout.flat_note(results, hidden)
    size = layout.figure_size(n_cols, len(rows), title=bool(title), note=bool(note))
    width, height = (round(v * DPI) for v in size)
    canvas = Canvas(width, height)
    panels = [[_PanelView(results, name) for name in row] for row in rows]
    xlim = time_limits(results.t)
    boxes = _layout(canvas, panels, n_cols, xlim, title, note)
    placed = [(panel, boxes[i][j]) for i, row in enumerate(panels)
              for j, panel in enumerate(row)]
    for panel, box in placed:
        panel.draw_inside(canvas, box, results, xlim)
    canvas.clear_outside([box for _, box in placed])    # matplotlib clips lines to the axes
    bottom = layout.last_in_column(panels)
    for i, row in enumerate(panels):
        for j, panel in enumerate(row):
            panel.draw_around(canvas, boxes[i][j], xlim, last=bottom[j] == i)
    if title:
        canvas.text((width / 2, EDGE * PX), title, SUPTITLE, valign="top")
    if note:
        canvas.text((EDGE * PX, height - EDGE * PX), note, SMALL, "l", "bottom", fill=NOTE)
    return canvas.image()


# -- the figure: panel boxes from measured texts, then each panel drawn ----------------------

class _PanelView:
    """A panel's texts and curves (``plotlayout.Panel``), and its value axis limits."""

    def __init__(self, results, name):
        meta = layout.Panel(results, name)
        self.title, self.ylabel = meta.title, meta.ylabel
        values = np.asarray(results[name], dtype=float)
        self.curves = [values] if values.ndim == 1 else list(values.T)
        self.legend = ["xyz"[k % 3] for k in range(len(self.curves))] if values.ndim == 2 else []
        self.ylim = padded(values)
        self.events = [e["t"] for e in (getattr(results, "stats", None) or {}).get("events", ())]

    def axes(self, box, xlim):
        x0, y0, x1, y1 = box
        return (Axis(*xlim, (x1 - x0) / PX, 3, FONT), Axis(*self.ylim, (y1 - y0) / PX, 2, FONT))

    def mapping(self, box, xlim):
        """(x axis, y axis, time -> pixel column, value -> pixel row) of the panel in ``box``
        (x0, y0, x1, y1: pixels of the file, y down)."""
        x0, y0, x1, y1 = box
        xaxis, yaxis = self.axes(box, xlim)
        to_x = lambda v: x0 + (np.asarray(v) - xaxis.low) / (xaxis.high - xaxis.low) * (x1 - x0)
        to_y = lambda v: y1 - (np.asarray(v) - yaxis.low) / (yaxis.high - yaxis.low) * (y1 - y0)
        return xaxis, yaxis, to_x, to_y

    def draw_inside(self, canvas, box, results, xlim):
        """Grid, events and curves (what spills over is cleared afterwards)."""
        x0, y0, x1, y1 = box
        xaxis, yaxis, to_x, to_y = self.mapping(box, xlim)
        for x in to_x(xaxis.ticks):
            canvas.line([(x, y0), (x, y1)], GRID, SPINE)
        for y in to_y(yaxis.ticks):
            canvas.line([(x0, y), (x1, y)], GRID, SPINE)
        for x in to_x(self.events):
            canvas.dotted(x, y0, y1, EVENT, 0.6)
        for k, values in enumerate(self.curves):
            for piece in _finite_pieces(to_x(results.t), to_y(values)):
                canvas.line(piece, TAB10[k % 10], LINE)

    def draw_around(self, canvas, box, xlim, last):
        """The frame, ticks and texts around the panel; tick labels and "time [s]" under the
        last panel of a column."""
        x0, y0, x1, y1 = box
        xaxis, yaxis, to_x, to_y = self.mapping(box, xlim)
        canvas.rectangle(box, SPINE)
        tick = TICK * PX
        for x in to_x(xaxis.ticks):
            canvas.line([(x, y1), (x, y1 + tick)], "black", SPINE)
        for y in to_y(yaxis.ticks):
            canvas.line([(x0 - tick, y), (x0, y)], "black", SPINE)
        reach = x0 - (TICK + TICK_PAD) * PX
        for y, label in zip(to_y(yaxis.ticks), yaxis.labels):
            canvas.text((reach, y), label, FONT, "r", "center")
        widest = max((canvas.width_of(s, FONT) for s in yaxis.labels), default=0.0)
        canvas.vertical_text((x0 - (TICK + TICK_PAD) * PX - widest - LABEL_PAD * PX,
                              (y0 + y1) / 2), self.ylabel, FONT)
        title_at = y0 - TITLE_PAD * PX
        if yaxis.offset:
            canvas.text((x0, y0 - 3.0 * PX), yaxis.offset, FONT, "l")
            # matplotlib lifts a title that would run into the "1e6" above the axis
            half = canvas.width_of(self.title, FONT) / 2
            if (x0 + x1) / 2 - half < x0 + canvas.width_of(yaxis.offset, FONT):
                title_at -= canvas.height_of(FONT) + 3.0 * PX
        canvas.text(((x0 + x1) / 2, title_at), self.title, FONT)
        if last:
            top = y1 + (TICK + TICK_PAD) * PX
            for x, label in zip(to_x(xaxis.ticks), xaxis.labels):
                canvas.text((x, top), label, FONT, valign="top")
            canvas.text(((x0 + x1) / 2, top + canvas.height_of(FONT) + LABEL_PAD * PX),
                        layout.TIME_LABEL, FONT, valign="top")
        self._draw_legend(canvas, box)

    def _draw_legend(self, canvas, box):
        """x, y, z right of the panel, where matplotlib puts an outside legend (plot.py)."""
        if not self.legend:
            return
        size = SMALL * PX
        left = box[2] + 0.01 * (box[2] - box[0]) + 0.4 * size
        row = canvas.height_of(SMALL)
        y = box[1] + 0.4 * size + row / 2
        for k, label in enumerate(self.legend):
            canvas.line([(left, y), (left + 1.4 * size, y)], TAB10[k % 10], LINE)
            canvas.text((left + 2.2 * size, y), label, SMALL, "l", "center")
            y += row + 0.2 * size

    def legend_width(self, canvas):
        if not self.legend:
            return 0.0
        return (0.8 + 2.2) * SMALL * PX + max(canvas.width_of(s, SMALL) for s in self.legend)


def _finite_pieces(x, y):
    """The runs of finite points of a curve, as (x, y) lists: a nan ends a line."""
    ok = np.isfinite(x) & np.isfinite(y)
    edges = np.flatnonzero(np.diff(np.concatenate(([0], ok.astype(np.int8), [0]))))
    return [list(zip(x[a:b].tolist(), y[a:b].tolist())) for a, b in zip(edges[::2], edges[1::2])
            if b - a > 1]


def _layout(canvas, panels, n_cols, xlim, title, note):
    """The panels' boxes (x0, y0, x1, y1 in pixels, y down): the texts around each panel
    measured with Pillow, placed by ``plotlayout.panel_boxes`` as ``plot.py`` places them.
    Ticks are counted on the default subplot size first, as matplotlib does there."""
    n_rows = len(panels)
    width, height = canvas.width / PX, canvas.height / PX          # points
    guess = (0, 0, 0.775 * width / n_cols * PX, 0.77 * height / n_rows * PX)
    label_h = canvas.height_of(FONT) / PX
    left, right = [0.0] * n_cols, [0.0] * n_cols
    above, below = [0.0] * n_rows, [0.0] * n_rows
    last = layout.last_in_column(panels)
    for i, row in enumerate(panels):
        for j, panel in enumerate(row):
            xaxis, yaxis = panel.axes(guess, xlim)
            widest = max((canvas.width_of(s, FONT) for s in yaxis.labels), default=0.0) / PX
            left[j] = max(left[j], widest + TICK + TICK_PAD + LABEL_PAD + label_h)
            above[i] = max(above[i], label_h + TITLE_PAD + (label_h if yaxis.offset else 0.0))
            if panel.legend:
                right[j] = max(right[j], panel.legend_width(canvas) / PX
                               + 0.01 * width / n_cols)
            under = TICK
            if last[j] == i:
                under = label_h + TICK + TICK_PAD + LABEL_PAD + label_h
                if j == n_cols - 1 or j == len(row) - 1:
                    overhang = canvas.width_of(xaxis.labels[-1], FONT) / PX / 2 \
                        if xaxis.labels else 0.0
                    right[j] = max(right[j], overhang)
            below[i] = max(below[i], under)
    boxes = layout.panel_boxes((width, height), left, right, above, below,
                               [canvas.height_of(SUPTITLE) / PX] if title else [],
                               [canvas.height_of(SMALL) / PX] if note else [])
    if boxes is None:               # texts fill the figure (not at figure_size's sizes)
        boxes = [[(0.0, 0.0, 1.0, 1.0)] * n_cols for _ in range(n_rows)]
    return [[tuple(v * PX for v in box) for box in row] for row in boxes]


# -- drawing: Pillow at SCALE times the size, in the file's pixel coordinates ----------------

@functools.cache
def _font_file():
    """matplotlib's DejaVu Sans, found without importing matplotlib; None if absent."""
    spec = importlib.util.find_spec("matplotlib")
    for folder in (spec.submodule_search_locations or []) if spec else []:
        path = os.path.join(folder, "mpl-data", "fonts", "ttf", "DejaVuSans.ttf")
        if os.path.exists(path):
            return path
    return None


class Canvas:
    """An RGB image SCALE times the file's size, drawn in the file's pixel coordinates."""

    def __init__(self, width, height):
        self.width, self.height = width, height
        self._image = Image.new("RGB", (width * SCALE, height * SCALE), "white")
        self._draw = ImageDraw.Draw(self._image)
        self._fonts = {}
        self._texts = []                # drawn on the reduced image: FreeType antialiases

    def font(self, points):
        """DejaVu Sans of ``points`` at the file's resolution (texts are drawn there)."""
        if points not in self._fonts:
            path = _font_file()
            self._fonts[points] = ImageFont.truetype(path, points * PX) if path else \
                ImageFont.load_default(points * PX)
        return self._fonts[points]

    def width_of(self, text, points):
        return self.font(points).getlength(text)

    def height_of(self, points):
        """The height of a line of text as matplotlib measures it (the ink of "lp")."""
        _, top, _, bottom = self.font(points).getbbox("lp", anchor="ls")
        return bottom - top

    def line(self, points, fill, width_pt):
        """A polyline ``width_pt`` points wide, round where it turns (Pillow's own round
        joints cost a Python call per point: here only where a turn would show a notch)."""
        # Pillow truncates a wide line's ends to whole pixels: unshifted, the curves lie on
        # average within a tenth of a pixel of where they belong (tests/test_quickplot.py)
        xy = np.asarray(points, dtype=float) * SCALE
        width = max(1, round(width_pt * PX * SCALE))
        self._draw.line(xy.ravel().tolist(), fill=fill, width=width)
        if len(xy) > 2 and width > 2:
            d = np.diff(xy, axis=0)
            cross = d[:-1, 0] * d[1:, 1] - d[:-1, 1] * d[1:, 0]
            dot = (d[:-1] * d[1:]).sum(axis=1)
            r = width / 2
            for x, y in xy[1:-1][np.abs(np.arctan2(cross, dot)) > 0.15]:
                self._draw.ellipse((x - r, y - r, x + r, y + r), fill=fill)

    def dotted(self, x, y0, y1, fill, width_pt):
        """A vertical dotted line (matplotlib's ":": dots one line width long, 1.65 apart)."""
        on, off = width_pt * PX, 1.65 * width_pt * PX
        y = y0
        while y < y1:
            self.line([(x, y), (x, min(y + on, y1))], fill, width_pt)
            y += on + off

    def rectangle(self, box, width_pt):
        x0, y0, x1, y1 = (v * SCALE - 0.5 for v in box)
        w = max(1, round(width_pt * PX * SCALE))
        half = w / 2
        self._draw.rectangle((x0 - half, y0 - half, x1 + half, y1 + half), outline="black",
                             width=w)

    def text(self, xy, text, points, align="m", valign="baseline", fill="black"):
        """Text aligned as matplotlib aligns it: ``align`` "l", "m" or "r" of ``x``;
        ``valign`` "top" (the ink of "lp" below ``y``), "center" (the digits' height centred
        on it), "baseline" or "bottom" (the depth of "lp" above it)."""
        font = self.font(points)
        _, ascent, _, descent = font.getbbox("lp", anchor="ls")      # ascent < 0 < descent
        baseline = {"top": -ascent, "center": -ascent / 2, "baseline": 0.0,
                    "bottom": -descent}[valign]
        self._texts.append(lambda image, draw: draw.text(
            (xy[0], xy[1] + baseline), text, font=font, fill=fill, anchor=align + "s"))

    def vertical_text(self, xy, text, points, fill="black"):
        """Text turned a quarter left, its descent side (right) at ``x``, centred on ``y``."""
        font = self.font(points)
        _, ascent, _, descent = font.getbbox("lp", anchor="ls")
        length = math.ceil(font.getlength(text)) + 2
        strip = Image.new("L", (length, math.ceil(descent - ascent) + 2), 0)
        ImageDraw.Draw(strip).text((1, 1 - ascent), text, font=font, fill=255, anchor="ls")
        turned = strip.rotate(90, expand=True)
        x, y = round(xy[0]) - turned.width, round(xy[1] - turned.height / 2)
        self._texts.append(lambda image, draw: image.paste(
            fill, (x, y, x + turned.width, y + turned.height), turned))

    def clear_outside(self, boxes):
        """Paint white what lies outside ``boxes``: panels on a grid, one row's boxes
        sharing their top and bottom, each box's edges on the frame drawn next."""
        width, height = self._image.size
        rows = {}
        for x0, y0, x1, y1 in boxes:
            rows.setdefault((round(y0 * SCALE), round(y1 * SCALE)), []).append(
                (round(x0 * SCALE), round(x1 * SCALE)))
        white = []
        above = 0
        for (top, bottom), spans in sorted(rows.items()):
            white.append((0, above, width, top))
            left = 0
            for x0, x1 in sorted(spans):
                white.append((left, top, x0, bottom))
                left = x1 + 1
            white.append((left, top, width, bottom))
            above = bottom + 1
        white.append((0, above, width, height))
        for x0, y0, x1, y1 in white:
            if x1 > x0 and y1 > y0:
                self._draw.rectangle((x0, y0, x1 - 1, y1 - 1), fill="white")

    def image(self):
        """The file's pixels: the drawing reduced SCALE times (a box filter), texts on top."""
        image = self._image.reduce(SCALE)
        draw = ImageDraw.Draw(image)
        for text in self._texts:
            text(image, draw)
        return image
