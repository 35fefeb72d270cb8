"""Build vistrack with its kernels compiled ahead of time (see src/vistrack/_prebuilt.py).

Everything else is declared in pyproject.toml. Compiling the kernels needs numba and a C
compiler; without them vistrack installs all the same and compiles its kernels on first use.
"""

import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = Path(__file__).resolve().parent


class BuildKernels(build_ext):
    """Build ``vistrack._kernels`` with :func:`vistrack._prebuilt_build.build` (numba's
    ahead-of-time compiler, in parts compiled at once, one process and module a part)
    instead of compiling C sources."""

    def build_extension(self, ext: Extension) -> None:
        target = Path(self.get_ext_fullpath(ext.name)).resolve()
        if os.environ.get("VISTRACK_PREBUILT", "1") == "0":
            # `make` does so: it compiles them afterwards, with the environment's own numba
            print("VISTRACK_PREBUILT=0: vistrack's kernels are not compiled ahead of time now",
                  file=sys.stderr)
            return
        try:
            with tempfile.TemporaryDirectory() as cache:
                os.environ["NUMBA_CACHE_DIR"] = cache  # from source, not from a cache
                sys.path.insert(0, str(HERE / "src"))
                from vistrack._prebuilt import BUILD_INFO, built, part_files
                from vistrack._prebuilt_build import build

                here = HERE / "src" / "vistrack"
                info, why = built(here)
                if info is not None and not why and (here / target.name).exists():
                    # an editable install again (make lint, make docs): the build beside the
                    # sources is current
                    target.parent.mkdir(parents=True, exist_ok=True)
                    parts = part_files(target.name, info.get("parts", ["_kernels"]))
                    for name in (*parts, BUILD_INFO):
                        shutil.copyfile(here / name, target.parent / name)
                    return
                print("compiling vistrack's kernels ahead of time (a minute or two, in "
                      "parallel)", file=sys.stderr)
                build(target.parent, target.name)
        except Exception as e:  # noqa: BLE001 - any failure leaves compilation to first use
            print(f"warning: vistrack's kernels were not compiled ahead of time ({e!r}); "
                  "vistrack works the same and compiles them on first use", file=sys.stderr)

    def copy_extensions_to_source(self) -> None:
        """Editable installs: the extension and its build information beside the sources."""
        for ext in self.extensions:
            # where build_extension wrote it (get_ext_fullpath names the source tree now)
            built = Path(self.build_lib, self.get_ext_filename(self.get_ext_fullname(ext.name)))
            if built.exists():
                dest = HERE / "src" / "vistrack"
                # with its other parts (_kernels_1, ...) and vistrack._prebuilt.BUILD_INFO,
                # which names them; a new file each, as a running vistrack may have the old
                # one open
                from vistrack._prebuilt import BUILD_INFO, part_files

                info = json.loads((built.parent / BUILD_INFO).read_text(encoding="utf-8"))
                parts = part_files(built.name, info.get("parts", ["_kernels"]))
                for name in (*parts, BUILD_INFO):
                    tmp = dest / f".{name}.{os.getpid()}.tmp"
                    shutil.copyfile(built.parent / name, tmp)
                    os.replace(tmp, dest / name)


setup(ext_modules=[Extension("vistrack._kernels", sources=[], optional=True)],
      cmdclass={"build_ext": BuildKernels})
