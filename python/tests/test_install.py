"""`cmake --install` puts an importable package into site-packages under the prefix."""

import shutil
import subprocess
import sys

from conftest import BUILD


def test_installed_package_imports_and_reads_a_map(tmp_path, yard_map):
    prefix = tmp_path / "prefix"
    # cmake --install writes install_manifest_python.txt into the build folder: leave it as it was.
    manifest = BUILD / "install_manifest_python.txt"
    before = manifest.read_bytes() if manifest.exists() else None
    try:
        subprocess.run(["cmake", "--install", str(BUILD), "--prefix", str(prefix), "--component", "python"],
                       check=True, capture_output=True)
    finally:
        if before is None:
            manifest.unlink(missing_ok=True)
        else:
            manifest.write_bytes(before)
    cache = (BUILD / "CMakeCache.txt").read_text()
    site = next(line.split("=", 1)[1] for line in cache.splitlines() if line.startswith("SSTA_PYTHON_INSTALL_DIR:"))
    package = prefix / site / "ssta"
    assert {p.name for p in package.iterdir()} >= {"__init__.py", "_ssta.pyi", "py.typed"}
    assert any(p.name.startswith("_ssta.") and p.suffix == ".so" for p in package.iterdir())
    # A clean interpreter that sees only the installed copy (not the build tree).
    probe = ("import ssta, sys; m = ssta.Map.open(sys.argv[1]); "
             "print(ssta.__file__); print(m.query([[3.0, 0.0]])['class'][0])")
    result = subprocess.run([sys.executable, "-c", probe, str(yard_map)], capture_output=True, text=True,
                            cwd=tmp_path, env={"PYTHONPATH": str(prefix / site), "PATH": "/usr/bin:/bin"})
    assert result.returncode == 0, result.stderr
    installed_init, cls = result.stdout.split()
    assert installed_init.startswith(str(package)) and cls == "1"
    shutil.rmtree(prefix)
