# Sourced by the tools: one cargo profile and one target directory that survives between
# runs (the first shaderc build takes minutes), and a runtime dir for the Vulkan loader.
export PATH="$HOME/.cargo/bin:$PATH"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/voxgi/target}"
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
    export XDG_RUNTIME_DIR="${TMPDIR:-/tmp}/voxgi-xdg-$(id -u)"
fi
mkdir -p "$XDG_RUNTIME_DIR" "$CARGO_TARGET_DIR"
chmod 700 "$XDG_RUNTIME_DIR" 2>/dev/null || true

# Link the shader compiler against Debian's shaderc (tools/setup installs libshaderc-dev)
# instead of compiling shaderc, glslang and SPIRV-Tools from source (27 minutes on 2 cores;
# this way the first build takes about 6). shaderc-sys looks for `libshaderc_shared.so`;
# Debian's static `libshaderc_combined.a` holds shaderc alone and its glslang and SPIRV-Tools
# come as static libraries of their own, so that name is a linker script that links them all.
if [ -z "${SHADERC_LIB_DIR:-}" ]; then
    libdir=/usr/lib/"$(uname -m)"-linux-gnu
    if [ -e "$libdir/libshaderc_combined.a" ] && [ -e "$libdir/libglslang.a" ]; then
        export SHADERC_LIB_DIR="$CARGO_TARGET_DIR/shaderc-lib"
        mkdir -p "$SHADERC_LIB_DIR"
        static="$libdir/libshaderc_combined.a"
        for l in glslang MachineIndependent GenericCodeGen OSDependent OGLCompiler SPIRV \
                 SPIRV-Tools-opt SPIRV-Tools glslang-default-resource-limits; do
            [ -e "$libdir/lib$l.a" ] && static="$static $libdir/lib$l.a"
        done
        script="GROUP ( $static )"
        if [ "$(cat "$SHADERC_LIB_DIR/libshaderc_shared.so" 2>/dev/null)" != "$script" ]; then
            rm -f "$SHADERC_LIB_DIR/libshaderc_shared.so"
            echo "$script" >"$SHADERC_LIB_DIR/libshaderc_shared.so"
        fi
    fi
fi
