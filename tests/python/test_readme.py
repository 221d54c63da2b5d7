"""The README's "Use it from C++" and "Use it from Python" examples are the ones the tests run: the C++ one is
examples/embed (built by CTest Install.EmbedExample), the Python one is run here."""
import os
import pathlib
import re
import subprocess
import sys

SOURCE = pathlib.Path(os.environ.get("DELTAGI_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))


def code_blocks(section, language):
    readme = (SOURCE / "README.md").read_text()
    start = readme.index("## " + section + "\n")
    end = readme.find("\n## ", start + 1)
    return re.findall(r"```" + language + r"\n(.*?)```", readme[start:end], re.S)


def test_the_cpp_example_is_examples_embed():
    cmake, = code_blocks("Use it from C++", "cmake")
    cpp, = code_blocks("Use it from C++", "cpp")
    assert cmake == (SOURCE / "examples/embed/CMakeLists.txt").read_text().split("\n", 2)[2]  # less the comment
    assert cpp == (SOURCE / "examples/embed/main.cpp").read_text()


def test_the_python_example_runs(tmp_path):
    code, = code_blocks("Use it from Python", "python")
    (tmp_path / "examples").symlink_to(SOURCE / "examples")
    (tmp_path / "out").mkdir()
    result = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "out/ball.png").exists()
    assert "(120, 160, 3)" in result.stdout
