# Shared helpers of scripts/test, scripts/run and .ci/run. Source it, do not run it.
#
#   ensure_packages PKG...   apt-get install the Debian packages that are missing
#                            (as root, else with sudo); does nothing off Debian
#   ensure_rust              make `cargo` available, installing rustup's stable
#                            toolchain (with rustfmt and clippy) if there is none
#   repo_root                the repository root

repo_root() {
    cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd
}

# Runs a command as root: directly, or with sudo (non-interactive without a terminal).
as_root() {
    if [ "$(id -u)" -eq 0 ]; then
        "$@"
    elif command -v sudo >/dev/null 2>&1; then
        if [ -t 0 ]; then sudo "$@"; else sudo -n "$@"; fi
    else
        echo "error: need root to run: $* (not root, and no sudo)" >&2
        return 1
    fi
}

ensure_packages() {
    if ! command -v dpkg-query >/dev/null 2>&1 || ! command -v apt-get >/dev/null 2>&1; then
        echo "note: not a Debian system; make sure these are installed: $*" >&2
        return 0
    fi
    local missing=() pkg
    for pkg in "$@"; do
        if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q 'install ok installed'; then
            missing+=("$pkg")
        fi
    done
    if [ "${#missing[@]}" -eq 0 ]; then
        return 0
    fi
    echo "installing: ${missing[*]}" >&2
    as_root env DEBIAN_FRONTEND=noninteractive apt-get update -q
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
}

ensure_rust() {
    if ! command -v cargo >/dev/null 2>&1 && [ -x "$HOME/.cargo/bin/cargo" ]; then
        export PATH="$HOME/.cargo/bin:$PATH"
    fi
    if command -v cargo >/dev/null 2>&1; then
        return 0
    fi
    echo "installing the Rust toolchain with rustup (stable, minimal, rustfmt, clippy)" >&2
    ensure_packages ca-certificates curl gcc libc6-dev
    curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs |
        sh -s -- -y --no-modify-path --profile minimal --default-toolchain stable --component rustfmt,clippy
    export PATH="$HOME/.cargo/bin:$PATH"
}

# What building and testing dirt needs on Debian: a C linker, numpy for the
# independent check, Vulkan (lavapipe) for the GPU tests, and real assets.
TEST_PACKAGES=(ca-certificates curl gcc libc6-dev python3 python3-numpy mesa-vulkan-drivers libvulkan1 assimp-testmodels)
# What `scripts/run` needs.
RUN_PACKAGES=(ca-certificates curl gcc libc6-dev python3 python3-numpy mesa-vulkan-drivers libvulkan1)
# What `scripts/eval` needs: the above and Embree 3 (a peer); node/npm for the
# bunny only where there is no npm yet (a nodejs from elsewhere may bundle it).
EVAL_PACKAGES=("${TEST_PACKAGES[@]}" libembree-dev)

# The browser build: the wasm32 target and wasm-bindgen-cli at exactly the
# version of wasm-bindgen in Cargo.lock (the CLI and the crate must match),
# installed into target/tools/bin (a debug build: it compiles in about two
# minutes and runs fast enough), which is put on PATH.
ensure_wasm_tools() {
    rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown ||
        rustup target add wasm32-unknown-unknown
    local version
    version=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/[^0-9.]/, ""); print; exit }' Cargo.lock)
    export PATH="$PWD/target/tools/bin:$PATH"
    if [ "$(wasm-bindgen --version 2>/dev/null)" != "wasm-bindgen $version" ]; then
        echo "installing wasm-bindgen-cli $version into target/tools" >&2
        cargo install --quiet --debug --root target/tools wasm-bindgen-cli --version "=$version"
    fi
}

# What the browser tests need: Debian's Chromium and its WebDriver.
BROWSER_PACKAGES=(chromium chromium-driver)
