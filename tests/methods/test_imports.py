import subprocess
import sys


def test_methods_import_only_numpy_scipy_and_the_core():
    code = (
        "import sys, sandbox.methods\n"
        "heavy = {'pybullet', 'meshcat', 'gymnasium', 'filterpy', 'matplotlib', 'tqdm'}\n"
        "print(sorted(heavy & set(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
