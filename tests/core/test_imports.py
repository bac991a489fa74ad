import subprocess
import sys


def test_core_imports_only_numpy_and_scipy():
    code = (
        "import sys, sandbox.core\n"
        "heavy = {'pybullet', 'meshcat', 'gymnasium', 'filterpy', 'matplotlib', 'tqdm', "
        "'numba'}\n"
        "print(sorted(heavy & set(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
