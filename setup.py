"""The wheel's build step (everything else is in pyproject.toml).

A wheel carries what a clone has beside the package, so that installed anywhere it works the same:
- the top-level configs and the shipped checkpoints (``rocketdrl_ma.config.SHIPPED_FOLDERS``) as
  ``rocketdrl_ma/data/<folder>/...``, which ``rocketdrl_ma.config.resolve_shipped_path`` falls back to;
- the npm packages the web page imports, exactly the files the page server serves and their licences, as
  ``rocketdrl_ma/web/vendor/`` in ``node_modules``' layout, from the ``node_modules`` that ``npm ci`` installs from
  package-lock.json (``make web-deps``; the build runs ``npm ci`` itself if they are missing and npm is there,
  and fails if it is not: the wheel's ``rocketdrl-ma web`` needs them).

An editable install (``pip install -e``) copies nothing: there the repository itself is found.
"""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
#: folder -> the files of it that ship (glob patterns); keep the folders in step with config.SHIPPED_FOLDERS
SHIPPED = {"matches": ["*.yaml"], "minigames": ["*.yaml"], "server": ["*.yaml"], "leagues": ["*.yaml", "*.jsonl", "curves/*.yaml"],
           "policies": ["*.yaml", "checkpoints/*.pt", "checkpoints/*.json"]}
#: what of node_modules the page imports (rocketdrl_ma/web/bridge.py: vendor_files) and the licences
WEB_VENDOR = ["three/build/three.module.js", "three/build/three.core.js", "three/LICENSE", "three/package.json",
              "@msgpack/msgpack/dist.esm/**/*.mjs", "@msgpack/msgpack/LICENSE", "@msgpack/msgpack/package.json"]


def _copy(patterns: list[str], source: Path, target: Path) -> list[Path]:
    copied = []
    for pattern in patterns:
        for f in sorted(source.glob(pattern)):
            if f.is_file() and "optim" not in f.name:  # optimizer states are for resuming training, not shipped
                out = target / f.relative_to(source)
                out.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(f, out)
                copied.append(out)
    return copied


class BuildPyWithData(build_py):
    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        package = Path(self.build_lib) / "rocketdrl_ma"
        for folder, patterns in SHIPPED.items():
            if not _copy(patterns, ROOT / folder, package / "data" / folder):
                raise SystemExit(f"build: nothing to ship from {folder}/ (run the build from the repository)")
        node_modules = ROOT / "node_modules"
        if not (node_modules / "three" / "build" / "three.module.js").is_file() and shutil.which("npm"):
            subprocess.run(["npm", "ci", "--no-audit", "--no-fund"], cwd=ROOT, check=True)  # as make web-deps
        copied = _copy(WEB_VENDOR, node_modules, package / "web" / "vendor")
        if not any(p.name == "three.module.js" for p in copied):
            raise SystemExit(f"build: three.js is not in {node_modules} and npm is not installed; run `npm ci` "
                             "(make web-deps) first: the wheel ships the web page's three.js")


setup(cmdclass={"build_py": BuildPyWithData})
