"""A wiring diagram as SVG (``svg``): blocks where the layout puts them, their ports in
Modelica's colours on the sides the blocks give them, the routed wires, the junction dots."""

import math
from xml.sax.saxutils import escape, quoteattr

import networkx as nx

from ..components.base import ANY
from ..graph.subsystem import Subsystem
from .blocks import (DOMAINS, LABEL_PX, LIBRARIES, NAME_PX, OUTWARD, ROUTED, ROW, STUB, TYPE_PX,
                     Block, connections_of, library_of, placement, port_domain, text_width)
from .layout import place_blocks
from .routing import Router, sign, simplify, spread, wire_junctions


def svg(model):
    """The wiring diagram of ``model`` as SVG text: blocks where ``auto_layout`` puts them,
    ports on their sides in Modelica's colours, orthogonal wires. A model of subsystems is
    drawn one level deep (each subsystem a block with its exposed ports); a half-built
    model (ports left open, no layout) draws too."""
    boxes = {name: Block(comp, *placement(model, name)) for name, comp in model.components.items()}
    spots = place_blocks(model, boxes)
    links = connections_of(model)
    _face_ports(boxes, spots, links)
    nets = _nets(model)
    ends = {}
    for name, box in boxes.items():
        x, y = spots[name]
        for port, (dx, dy) in box.at.items():
            ends[(name, port)] = ((x + dx, y + dy), OUTWARD[box.sides[port]])
    order = sorted(range(len(links)), key=lambda k: (_distance(ends, links[k]), k))
    routed = [None] * len(links)
    stubs = [(x + d[0] * STUB, y + d[1] * STUB) for (x, y), d in ends.values()]
    router = Router([(spots[n][0], spots[n][1], b.w, b.h) for n, b in boxes.items()], stubs)
    for k in order:
        a, pa, b, pb = links[k]
        (pa_xy, da), (pb_xy, db) = ends[(a, pa)], ends[(b, pb)]
        net = nets[(a, pa)]
        if len(links) > ROUTED:
            stub_a = (pa_xy[0] + da[0] * STUB, pa_xy[1] + da[1] * STUB)
            stub_b = (pb_xy[0] + db[0] * STUB, pb_xy[1] + db[1] * STUB)
            points = simplify([pa_xy, stub_a, (stub_b[0], stub_a[1]), stub_b, pb_xy])
        else:
            points = router.route(pa_xy, da, pb_xy, db, net)
        routed[k] = (points, net)
    spread(routed, router.blocks)
    return _draw(model, boxes, spots, links, routed, nets)


def _distance(ends, link):
    (p, _), (q, _) = ends[(link[0], link[1])], ends[(link[2], link[3])]
    return abs(p[0] - q[0]) + abs(p[1] - q[1])


def _face_ports(boxes, spots, links):
    """Top and bottom ports face the blocks they are wired to (an axis wired only to a
    probe below moves to the bottom); a part with one port turns it to what it meets."""
    peers = {}
    for a, pa, b, pb in links:
        peers.setdefault((a, pa), []).append((b, pb))
        peers.setdefault((b, pb), []).append((a, pa))

    def centre(name):
        return spots[name][0] + boxes[name].w / 2, spots[name][1] + boxes[name].h / 2
    for name, box in boxes.items():
        if box.single or box.turned:
            continue
        ends = [p for p, side in box.sides.items() if side in ("top", "bottom")]
        chosen = {}
        for port in ends:
            ys = [centre(other)[1] for other, _ in peers.get((name, port), ()) if other != name]
            if ys:
                mean, y = sum(ys) / len(ys), spots[name][1]
                chosen[port] = "top" if mean < y else "bottom" if mean > y + box.h else \
                    box.sides[port]
        # ports wired to nothing follow the others (an elbow's support follows its axis)
        if len(set(chosen.values())) == 1:
            side = next(iter(chosen.values()))
            chosen.update({p: side for p in ends if p not in chosen})
        if any(box.sides[p] != side for p, side in chosen.items()):
            box.sides.update(chosen)
            box.arrange()
    for name, box in boxes.items():
        if not box.single or box.turned:
            continue
        for port in box.sides:
            others = [o for o in peers.get((name, port), ()) if o[0] != name]
            if not others:
                continue
            other, oport = others[0]
            ox, oy = spots[other][0] + boxes[other].at[oport][0], \
                spots[other][1] + boxes[other].at[oport][1]
            x, y = spots[name]
            beyond = {"left": x - ox, "right": ox - x - box.w,
                      "top": y - oy, "bottom": oy - y - box.h}
            if not box.probe and boxes[other].sides[oport] in ("left", "right"):
                beyond["top"] = beyond["bottom"] = -math.inf
            box.sides[port] = max(beyond, key=lambda s: (beyond[s], s in ("left", "right")))
        box.arrange()


def _nets(model):
    """Each port's connection set: (component, port) -> net number."""
    graph = nx.Graph()
    for a, b in model.connections:
        graph.add_edge((a.component.name, a.name), (b.component.name, b.name))
    out = {}
    components = sorted((sorted(c, key=str) for c in nx.connected_components(graph)),
                        key=lambda c: str(c[0]))
    for i, members in enumerate(components):
        for member in members:
            out[member] = i
    return out


def _net_domain(model, nets):
    domains = {}
    for (name, port), net in nets.items():
        domain = port_domain(model.components[name], port)
        if domain != ANY:
            domains.setdefault(net, domain)
    return domains


def _f(v):
    """A coordinate as SVG text: short, exact for the halves layouts give."""
    return f"{round(v, 1):g}"


def _path(points, radius=4.0):
    """SVG path data: straight runs with rounded corners."""
    d = [f"M{_f(points[0][0])},{_f(points[0][1])}"]
    for p, c, n in zip(points, points[1:], points[2:]):
        r = min(radius, math.dist(p, c) / 2, math.dist(c, n) / 2)
        a = (c[0] + sign(p[0] - c[0]) * r, c[1] + sign(p[1] - c[1]) * r)
        b = (c[0] + sign(n[0] - c[0]) * r, c[1] + sign(n[1] - c[1]) * r)
        d.append(f"L{_f(a[0])},{_f(a[1])} Q{_f(c[0])},{_f(c[1])} {_f(b[0])},{_f(b[1])}")
    d.append(f"L{_f(points[-1][0])},{_f(points[-1][1])}")
    return " ".join(d)


def _draw(model, boxes, spots, links, routed, nets):
    domains = _net_domain(model, nets)
    xs, ys = [], []
    for name, (x, y) in spots.items():
        xs += [x - 30, x + boxes[name].w + 30]
        ys += [y - 16, y + boxes[name].h + 16]
    for points, _ in routed:
        xs += [p[0] for p in points]
        ys += [p[1] for p in points]
    if not xs:
        xs, ys = [0, 200], [0, 60]
    x0, y0 = math.floor(min(xs)) - 12, math.floor(min(ys)) - 12
    width, height = math.ceil(max(xs)) + 12 - x0, math.ceil(max(ys)) + 12 - y0
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{x0} {y0} {width} {height}" '
           f'width="{width}" height="{height}" font-family="Helvetica, Arial, sans-serif">',
           f"<title>{escape(model.name)}</title>",
           f'<rect x="{x0}" y="{y0}" width="{width}" height="{height}" fill="#ffffff"/>',
           '<g class="wires" fill="none" stroke-linejoin="round">']
    for (a, pa, b, pb), (points, net) in zip(links, routed):
        colour, stroke = DOMAINS[domains.get(net, ANY)]
        out.append(f'<path class="wire" data-from="{a}.{pa}" data-to="{b}.{pb}" '
                   f'stroke="{colour}" stroke-width="{stroke}" d="{_path(points)}"/>')
    for (x, y), net in wire_junctions(routed):
        colour, stroke = DOMAINS[domains.get(net, ANY)]
        out.append(f'<circle class="junction" cx="{_f(x)}" cy="{_f(y)}" r="{stroke + 1.6:g}" '
                   f'fill="{colour}"/>')
    out.append("</g>")
    turns = {}                      # which way wires turn after leaving a port: labels avoid it
    for (a, pa, b, pb), (points, _) in zip(links, routed):
        for end, path in (((a, pa), points), ((b, pb), points[::-1])):
            if len(path) > 2:
                turns.setdefault(end, set()).add(sign(path[2][0] - path[1][0]))
    for name, box in boxes.items():
        out += _block(box, *spots[name], domains, nets, turns)
    out.append("</svg>")
    return "\n".join(out) + "\n"


def _block(box, x, y, domains, nets, turns):
    comp = box.comp
    library = library_of(comp)
    border, fill = LIBRARIES.get(library, LIBRARIES["multibody"])
    kind = comp.type_name if not isinstance(comp, Subsystem) else comp.definition.name
    out = [f'<g class="block" data-name="{box.name}" data-type={quoteattr(kind or "")} '
           f'data-x="{_f(x)}" data-y="{_f(y)}" data-w="{box.w}" data-h="{box.h}">',
           f"<title>{escape(box.name)}: {escape(kind or '')}</title>"]
    if library == "subsystem":        # a stack of sheets: a model inside
        out.append(f'<rect x="{_f(x + 3)}" y="{_f(y + 3)}" width="{box.w}" height="{box.h}" '
                   f'rx="5" fill="{fill}" stroke="{border}" stroke-width="1"/>')
    radius = box.h / 2 if box.probe else 5
    out.append(f'<rect class="body" x="{_f(x)}" y="{_f(y)}" width="{box.w}" height="{box.h}" '
               f'rx="{_f(radius)}" fill="{fill}" stroke="{border}" stroke-width="1.2"/>')
    cx = x + box.w / 2
    if box.probe:
        out.append(_glyph("probe", x + 12, y + box.h / 2, border))
        out.append(f'<text x="{_f(x + 22)}" y="{_f(y + box.h / 2 + 3.2)}" font-size="9" '
                   f'fill="#1a1a1a">{escape(box.name)}</text>')
    else:
        out.append(f'<text x="{_f(cx)}" y="{_f(y + 13)}" font-size="{NAME_PX}" '
                   f'font-weight="bold" text-anchor="middle" fill="#1a1a1a">'
                   f"{escape(box.name)}</text>")
        out.append(f'<text x="{_f(cx)}" y="{_f(y + 17 + box.rows * ROW + 10)}" '
                   f'font-size="{TYPE_PX:g}" '
                   f'text-anchor="middle" fill="#6e6e6e">{escape(box.kind)}</text>')
        labels = [p for p in comp.ports if box.sides[p] in ("left", "right")]
        room = box.w - 2 * max((text_width(p, LABEL_PX) for p in labels), default=0) - 18
        if room >= 14:
            gy = y + 17 + box.rows * ROW / 2
            glyph = _glyph(library, cx, gy, border)
            # the sign turns and mirrors with its block; the texts never do (they would read
            # backwards)
            if box.turned:
                mirror = f" translate({_f(2 * cx)},0) scale(-1,1)" if box.flip else ""
                glyph = f'<g transform="rotate({box.rotation} {_f(cx)} {_f(gy)}){mirror}">' \
                        f"{glyph}</g>"
            out.append(glyph)
    for port, (dx, dy) in box.at.items():
        px, py = x + dx, y + dy
        side = box.sides[port]
        domain = port_domain(comp, port)
        if domain == ANY:
            domain = domains.get(nets.get((box.name, port)), ANY)
        out.append(_marker(comp, port, side, domain, px, py))
        if box.probe:
            continue
        # beside a top or bottom port: outwards when two share the side; else away from
        # where its wires turn
        pair = sum(1 for p in box.sides if box.sides[p] == side) == 2
        right = not (pair and dx < box.w / 2 - 1)
        taken = turns.get((box.name, port), set())
        if not pair and 1 in taken and -1 not in taken:
            right = False
        outward, shift = ("start", 5) if right else ("end", -5)
        anchor = {"left": ("start", px + 7, py + 2.5), "right": ("end", px - 7, py + 2.5),
                  "top": (outward, px + shift, py - 4), "bottom": (outward, px + shift, py + 8.5)}
        how, tx, ty = anchor[side]
        out.append(f'<text x="{_f(tx)}" y="{_f(ty)}" font-size="{LABEL_PX:g}" '
                   f'text-anchor="{how}" fill="#555555">{escape(port)}</text>')
    out.append("</g>")
    return out


def _marker(comp, port, side, domain, x, y):
    """A port's marker, centred on the block's edge: Modelica's shapes and colours."""
    colour = DOMAINS.get(domain, DOMAINS[ANY])[0]
    solid = port.endswith("_a") or comp.role == "world"
    head = f'<g class="port" data-port="{comp.name}.{port}" data-x="{_f(x)}" data-y="{_f(y)}">'
    if comp.ports[port].domain in ("signal_in", "signal_out"):
        inward = comp.ports[port].domain == "signal_in"
        ux, uy = OUTWARD[side]
        if inward:
            ux, uy = -ux, -uy
        tip = (x + ux * 4.5, y + uy * 4.5)
        back = (x - ux * 4.5, y - uy * 4.5)
        wing = (uy * 4.5, ux * 4.5)
        points = " ".join(f"{_f(px)},{_f(py)}" for px, py in
                          (tip, (back[0] + wing[0], back[1] + wing[1]),
                           (back[0] - wing[0], back[1] - wing[1])))
        fill = colour if inward else "#ffffff"
        shape = f'<polygon points="{points}" fill="{fill}" stroke="{colour}" stroke-width="1"/>'
    elif domain == "rotational":
        fill = colour if solid else "#ffffff"
        shape = (f'<circle cx="{_f(x)}" cy="{_f(y)}" r="4" fill="{fill}" stroke="{colour}" '
                 f'stroke-width="1.2"/>')
    elif domain in ("frame", "translational"):
        fill = colour if solid else "#ffffff" if domain == "translational" else "#c8c8c8"
        shape = (f'<rect x="{_f(x - 4)}" y="{_f(y - 4)}" width="8" height="8" fill="{fill}" '
                 f'stroke="{colour}" stroke-width="1.2"/>')
    else:
        shape = f'<circle cx="{_f(x)}" cy="{_f(y)}" r="3" fill="{colour}"/>'
    return head + shape + "</g>"


def _glyph(library, x, y, colour):
    """A small sign of the library, centred on (x, y)."""
    s = f'stroke="{colour}" stroke-width="1.1" fill="none"'
    if library == "multibody":          # a frame: two axes
        return (f'<path class="glyph" d="M{_f(x - 5)},{_f(y + 4)} h10 M{_f(x - 5)},{_f(y + 4)} '
                f'v-9 M{_f(x + 3)},{_f(y + 2)} l2,2 -2,2 M{_f(x - 7)},{_f(y - 3)} l2,-2 2,2" {s}/>')
    if library == "rotational":         # a turning arrow
        return (f'<path class="glyph" d="M{_f(x + 4)},{_f(y - 3)} A5,5 0 1 0 {_f(x + 5)},'
                f'{_f(y + 1)} M{_f(x + 2)},{_f(y - 4)} l2,1 1,-2.2" {s}/>')
    if library == "translational":      # a push both ways
        return (f'<path class="glyph" d="M{_f(x - 6)},{_f(y)} h12 M{_f(x - 3)},{_f(y - 3)} '
                f'l-3,3 3,3 M{_f(x + 3)},{_f(y - 3)} l3,3 -3,3" {s}/>')
    if library == "signals":            # a step
        return f'<path class="glyph" d="M{_f(x - 6)},{_f(y + 4)} h5 v-8 h7" {s}/>'
    if library == "probe":              # a dial
        return (f'<path class="glyph" d="M{_f(x - 5)},{_f(y + 3)} A5,5 0 0 1 {_f(x + 5)},'
                f'{_f(y + 3)} M{_f(x)},{_f(y + 3)} l3,-5" {s}/>')
    return (f'<path class="glyph" d="M{_f(x - 6)},{_f(y - 4)} h8 v6 h-8 z M{_f(x - 2)},'
            f'{_f(y)} h8 v6 h-8 z" {s}/>')
