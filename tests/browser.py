"""What the browser tests do where they cannot run."""

import os

import pytest


def browser_missing(why):
    """The browser tests cannot run here: a failure that says how to mend it, never a silent
    skip (a skipped browser test would let the studio regress unseen). Setting
    KINETWORK_SKIP_BROWSER=1 skips them knowingly, on a machine where Chromium cannot be had."""
    if os.environ.get("KINETWORK_SKIP_BROWSER") == "1":
        pytest.skip(why)
    pytest.fail(f"{why}; `make test` and .ci/run install it as root (.ci/chromium), or set "
                f"KINETWORK_SKIP_BROWSER=1 to skip the browser tests knowingly", pytrace=False)
