# Sourced by the tools: one cargo profile and one target directory that survives between
# runs (the first shaderc build takes minutes), and a runtime dir for the Vulkan loader.
export PATH="$HOME/.cargo/bin:$PATH"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/voxgi/target}"
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
    export XDG_RUNTIME_DIR="${TMPDIR:-/tmp}/voxgi-xdg-$(id -u)"
fi
mkdir -p "$XDG_RUNTIME_DIR" "$CARGO_TARGET_DIR"
chmod 700 "$XDG_RUNTIME_DIR" 2>/dev/null || true
