"""JSON load/save (placeholder until the io module lands)."""


def load(path):
    raise NotImplementedError


def save(model, path):
    raise NotImplementedError
