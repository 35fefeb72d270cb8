"""Build vistrack with its kernels compiled ahead of time (see src/vistrack/_prebuilt.py).

Everything else is declared in pyproject.toml. Compiling the kernels needs numba and a C
compiler; without them vistrack installs all the same and compiles its kernels on first use.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = Path(__file__).resolve().parent
INFO = "_kernels.json"  # vistrack._prebuilt.BUILD_INFO


class BuildKernels(build_ext):
    """Build ``vistrack._kernels`` with ``python -m vistrack._prebuilt_build`` (numba's
    ahead-of-time compiler) instead of compiling C sources."""

    def build_extension(self, ext: Extension) -> None:
        target = Path(self.get_ext_fullpath(ext.name))
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            [str(HERE / "src")] + ([os.environ["PYTHONPATH"]] if "PYTHONPATH" in os.environ
                                   else [])))
        cmd = [sys.executable, "-m", "vistrack._prebuilt_build", "build", "--out", str(target)]
        print("compiling vistrack's kernels ahead of time (a minute or two)", file=sys.stderr)
        try:
            subprocess.run(cmd, check=True, env=env, cwd=HERE)
        except (OSError, subprocess.CalledProcessError) as e:
            print(f"warning: vistrack's kernels were not compiled ahead of time ({e}); "
                  "vistrack works the same and compiles them on first use", file=sys.stderr)

    def copy_extensions_to_source(self) -> None:
        """Editable installs: the extension and its build information beside the sources."""
        for ext in self.extensions:
            built = Path(self.get_ext_fullpath(ext.name))
            if built.exists():
                dest = HERE / "src" / "vistrack"
                for name in (built.name, INFO):  # a new file each: a running vistrack may
                    tmp = dest / f".{name}.{os.getpid()}.tmp"  # have the old one open
                    shutil.copyfile(built.parent / name, tmp)
                    os.replace(tmp, dest / name)


setup(ext_modules=[Extension("vistrack._kernels", sources=[], optional=True)],
      cmdclass={"build_ext": BuildKernels})
