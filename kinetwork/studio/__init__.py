"""The browser studio: place, wire, run and watch models in a page served on this machine.

``kinetwork studio [MODEL]`` starts it (:func:`cli_studio`); ``server.create_app`` is the
ASGI app, whose HTTP API ``API.md`` describes. FastAPI and uvicorn are needed only here
(``pip install kinetwork[studio]``), so they are imported when the studio starts.
"""

from .launch import cli_studio

__all__ = ["cli_studio"]
