"""The files a URDF's ``<mesh filename>`` names, found the way ROS tools find them.

``package://PKG/path`` is ``path`` inside the package folder of PKG: one named PKG on
``ROS_PACKAGE_PATH`` (ROS 1), ``PREFIX/share/PKG`` for a prefix on ``AMENT_PREFIX_PATH``
(ROS 2), or, as a URDF shipped inside its package (example-robot-data, a robot's
``*_description`` folder) is usually read, a folder above the URDF file that is named PKG, holds
a ``package.xml`` naming PKG, or has PKG under its ``share``. ``file://`` and plain paths are
files, a relative one relative to the URDF's folder.
"""

import os
import re

PACKAGE_NAME = re.compile(r"<name>\s*([^<\s]+)\s*</name>")


def resolve(filename, urdf_folder):
    """The existing file ``filename`` names, as an absolute path, or None."""
    if not filename:
        return None
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://"):].partition("/")
        for root in package_folders(package, urdf_folder):
            path = os.path.join(root, rest)
            if os.path.isfile(path):
                return os.path.abspath(path)
        return None
    path = filename[len("file://"):] if filename.startswith("file://") else filename
    path = os.path.join(urdf_folder, path)          # an absolute path stays as it is
    return os.path.abspath(path) if os.path.isfile(path) else None


def package_folders(package, urdf_folder):
    """The folders that may be the package ``package``, the likeliest first."""
    for entry in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep):
        if entry:
            yield os.path.join(entry, package) if os.path.basename(entry) != package else entry
    for prefix in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        if prefix:
            yield os.path.join(prefix, "share", package)
    folder = os.path.abspath(urdf_folder)
    while True:
        if os.path.basename(folder) == package or _names(folder) == package:
            yield folder
        yield os.path.join(folder, "share", package)
        parent = os.path.dirname(folder)
        if parent == folder:
            return
        folder = parent


def _names(folder):
    """The package name in ``folder/package.xml``, if there is one."""
    try:
        with open(os.path.join(folder, "package.xml"), encoding="utf-8", errors="replace") as fh:
            found = PACKAGE_NAME.search(fh.read(20_000))
    except OSError:
        return None
    return found.group(1) if found else None
