"""The answer of a sweep or a Monte Carlo draw: an xarray Dataset, its summary lines and its
NetCDF file.

The Dataset has one dimension per swept parameter (or ``member``, with the drawn values as
coordinates), then ``t`` (the time, named as ``Results.to_xarray`` names it) and the
dimensions of vector signals (``axis``; ``row`` and ``col``); every kept state and probe
signal is a variable with its unit; ``status``, ``reason``, ``t_reached`` and ``method`` say
how each member ended.
"""

import numpy as np

from ..solver.results import TIME, signal_coords, signal_dims


def dataset(plan, layout, members, attrs):
    """The Dataset of ``members`` (a ``batch.Members``) laid out as ``layout`` says (built
    without importing dask.array: ``xrdata``)."""
    from .xrdata import dataset as xr_dataset
    keep = members.keep
    dims, shape = layout["dims"], layout["shape"]
    grid = plan.grid
    data = {}
    for k, (name, unit) in enumerate(zip(keep.state_names, keep.state_units)):
        data[name] = (dims + [TIME], members.states[:, :, k].reshape(*shape, len(grid)),
                      {"units": unit, "kind": "state"})
    col = 0
    system = plan.system
    for sig in keep.signals:
        block = members.outputs[:, :, col:col + sig.size]
        col += sig.size
        attrs_ = {"units": sig.unit, "kind": "probe", "probe": sig.probe,
                  "quantity": sig.quantity}
        target = system.probe_targets.get(sig.probe)
        if target:
            attrs_["port"] = target
        data[sig.name] = (dims + [TIME, *signal_dims(sig.shape)],
                          block.reshape(*shape, len(grid), *sig.shape), attrs_)
    data["status"] = (dims, np.array(members.status, dtype=object).reshape(shape),
                      {"doc": "ok, failed (see reason) or interrupted"})
    data["reason"] = (dims, np.array(members.reason, dtype=object).reshape(shape),
                      {"doc": "why a member failed"})
    data["t_reached"] = (dims, members.t_reached.reshape(shape),
                         {"units": "s", "doc": "the time a member's run reached"})
    data["method"] = (dims, np.array(members.method, dtype=object).reshape(shape),
                      {"doc": "the integration method that ran the member"})
    coords = {TIME: (TIME, grid, {"units": "s", "long_name": "time"}),
              **signal_coords(keep.signals)}
    for name, values in layout["coords"].items():
        coords[name] = (name, values, {"units": layout["units"].get(name, "")})
    for name, values in layout.get("member_coords", {}).items():
        coords[name] = ("member", values, {"units": layout["units"].get(name, ""),
                                           "distribution": layout["distributions"][name]})
    s = plan.settings
    extra = {"lifted": plan.lifted.note} if plan.lifted is not None else {}
    return xr_dataset(data, coords, {
        "model": system.model.name, "method": plan.key, "rtol": s["rtol"],
        "atol": s["atol"], "t_start": plan.t_start, "t_end": float(s["t_end"]),
        "n_points": s["n_points"], "members": len(members.status),
        "failed": members.status.count("failed"), **extra, **attrs})


def param_unit(plan, name):
    """The unit of a varied parameter: a lifted path's, its component parameter's; a model
    parameter's, that of the component parameters it is given to as it is (``c`` given to a
    SpringDamper's ``c``: N.m/rad) when they agree; else ""."""
    if plan.lifted is not None and name in plan.lifted.units:
        return plan.lifted.units[name]
    units = set()
    for comp in plan.system.model.flat().components.values():
        for key, spec in comp.params.items():
            if comp._values.get(key) == name and isinstance(spec.unit, str):
                units.add(spec.unit)
    return units.pop() if len(units) == 1 else ""


def summary(ds):
    """A line per member: its parameter values, then the last value of each scalar probe
    signal, or its status and reason."""
    dims = list(ds.status.dims)
    probes = [n for n, v in ds.data_vars.items()
              if v.attrs.get("kind") == "probe" and v.dims == (*dims, TIME)]
    lines = ["  ".join(dims + probes)]
    for index in np.ndindex(*ds.status.shape):
        member = ds.isel(dict(zip(dims, index)))
        head = [f"{d}={member[d].item():g}" for d in dims]
        if member.status.item() == "ok":
            lines.append("  ".join(head + [f"{member[p].values[-1]:.6g}" for p in probes]))
        else:
            lines.append("  ".join([*head, f"{member.status.item()}: {member.reason.item()}"]))
    return "\n".join(lines)


def to_netcdf(ds, path):
    """The Dataset as NetCDF (strings as fixed text, so that scipy's writer takes them)."""
    out = ds.copy()
    for name in ("status", "reason", "method"):
        out[name] = out[name].astype(str)
    out.to_netcdf(path)
