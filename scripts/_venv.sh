# Shared by scripts/test and scripts/demo: create or refresh .venv with the given extras.
# Usage: source scripts/_venv.sh EXTRAS   (e.g. "test" or "")
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="$repo/.venv"
extras="${1:-}"
if [[ ! -x "$venv/bin/python" ]]; then
    python3 -m venv "$venv"
fi
stamp="$venv/.installed-${extras:-base}"
# Reinstall only when pyproject changed since the last install with these extras.
if [[ ! -f "$stamp" || "$repo/pyproject.toml" -nt "$stamp" ]]; then
    spec="$repo"
    [[ -n "$extras" ]] && spec="$repo[$extras]"
    # uv (Astral's installer, one wheel from PyPI) installs the same versions as pip in about
    # 10 s of wall where pip takes 85-90 s (docs/benchmarks.md, "scripts/test on a fresh clone");
    # pip stays the fallback (no network to PyPI, a platform uv has no wheel for).
    # uv reads neither pip's configuration nor its certificate settings: it gets the index pip
    # uses (PIP_INDEX_URL, else pip.conf's index-url, else PyPI) and the system's trust store.
    index="${PIP_INDEX_URL:-$("$venv/bin/python" -m pip config get global.index-url 2>/dev/null || true)}"
    if ! { "$venv/bin/python" -m pip install --quiet uv \
            && env UV_NATIVE_TLS=1 ${index:+UV_DEFAULT_INDEX="$index"} \
                "$venv/bin/uv" pip install --quiet --python "$venv/bin/python" -e "$spec"; }; then
        echo "== uv could not install: installing with pip"
        "$venv/bin/python" -m pip install --quiet --upgrade pip
        "$venv/bin/python" -m pip install --quiet -e "$spec"
    fi
    touch "$stamp"
fi
export PATH="$venv/bin:$PATH"
# Bytecode is written at first import (uv does not compile at install, as pip does): where
# PYTHONDONTWRITEBYTECODE is set, every process this venv starts (the tests start hundreds:
# coordinators, workers, slots, CLI runs) would compile numpy, scipy and the package again.
unset PYTHONDONTWRITEBYTECODE
# Compile the numba kernels once per installed tree, so that a first study does not
# (docs/benchmarks.md, "Cold start"): every kernel, the built-in functions' objectives and the
# map kernels (a suite's objective compiles at its first study, a few seconds); with the cache
# filled this prints nothing. Two processes (-j 2) share the pieces: on two cores about 0.6 of
# the wall time of one. A failure is not fatal: the kernels then compile at first use. A caller
# that has other work meanwhile sets defer_warmup=1 and runs warm_kernels itself (scripts/test:
# beside mypy, one process that would leave a core idle).
warm_kernels() {
    swarmpath warmup --if-cold --no-suites -j 2 || echo "== swarmpath warmup failed: the kernels compile at first use"
}
[[ -n "${defer_warmup:-}" ]] || warm_kernels
