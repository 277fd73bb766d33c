#!/usr/bin/env bash
# Makes the folder a GPU device session carries (see /work/.library/device/README.md): a device
# machine is bare, so the pack holds the installed loom (bin/, share/loom/ with shaders, graphs,
# scripts, scenes and the bench scripts), the Veach Ajar and SMS sphere scenes from
# ../shared/scenes, the shared libraries loom needs beyond glibc, and the Vulkan and GL loaders
# (the files of Debian's libvulkan1, libglvnd0, libglx0, libegl1 packages), compressed.
# It checks that the pack is under 64 MiB (what a device call carries, the repository included).
#
#   tools/device-pack.sh [--build DIR] [--out DIR]    (defaults: build/, carry/device-pack/)
#
# On the device, from the repository root:  bash carry/device-pack/run.sh   (README inside).
set -euo pipefail
cd "$(dirname "$0")/.."

build=build
out=carry/device-pack
limit=$((64 * 1024 * 1024))
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    -h|--help) sed -n 2,11p "$0"; exit 0 ;;
    *) echo "device-pack.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
[ -x "$build/apps/loom" ] || { echo "device-pack.sh: no loom in $build (cmake --build $build first)" >&2; exit 2; }
type=$(sed -n 's/^CMAKE_BUILD_TYPE:STRING=//p' "$build/CMakeCache.txt")
[ "$type" = Release ] || echo "device-pack.sh: warning: $build is a '$type' build, not Release" >&2

rm -rf "$out"
mkdir -p "$out"
out=$(cd "$out" && pwd)
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT

# 1. loom as installed (it finds its shaders in ../share/loom), without the GUI.
cmake --install "$build" --prefix "$out" --strip >/dev/null
rm -f "$out/bin/loom-inspector"
mkdir -p "$out/share/loom/bench"
cp bench/*.sh "$out/share/loom/bench/"

# 2. The scenes the suite times at 1080p, where this checkout has them.
if [ -d ../shared/scenes ]; then
  mkdir -p "$out/share/loom/scenes/shared"
  for s in veach-ajar sms-sphere; do
    [ -d "../shared/scenes/$s" ] && cp -r "../shared/scenes/$s" "$out/share/loom/scenes/shared/"
  done
fi

# 3. Shared libraries. glibc's own stay behind (a newer glibc runs this build); libstdc++ and
# libgcc_s go to lib/fallback, used only where the device's are older than this build's.
mkdir -p "$stage/lib/fallback"
ldd "$build/apps/loom" | awk '$2 == "=>" && $3 ~ /^\// {print $1, $3}' | while read -r name path; do
  case "$name" in
    libc.so.*|libm.so.*|libdl.so.*|libpthread.so.*|librt.so.*|ld-linux*) ;;
    libstdc++.so.*|libgcc_s.so.*) cp -L "$path" "$stage/lib/fallback/$name" ;;
    *) cp -L "$path" "$stage/lib/$name" ;;
  esac
done
# The loaders, unpacked from the installed Debian packages (the device has none): the Vulkan
# loader and glvnd's dispatch library, which NVIDIA's Vulkan driver (libGLX_nvidia) links;
# GLX and EGL where installed.
for pkg in libvulkan1 libglvnd0 libglx0 libegl1; do
  if ! dpkg -L "$pkg" >/dev/null 2>&1; then
    case "$pkg" in
      libvulkan1|libglvnd0) echo "device-pack.sh: package $pkg is not installed" >&2; exit 2 ;;
      *) continue ;;
    esac
  fi
  dpkg -L "$pkg" | grep -E '/lib[^/]*\.so\.[0-9]+$' | while read -r f; do cp -L "$f" "$stage/lib/"; done
done
# What the build links against, for the README.
(cd "$stage/lib" && ls) >"$out/LIBRARIES"
tar -C "$stage" -cf - lib | xz -6 -T2 >"$out/lib.tar.xz"

# 4. What to run there.
cp tools/device-pack/run.sh "$out/run.sh"
chmod +x "$out/run.sh"
{
  cat tools/device-pack/README
  echo
  echo "Packed $(date -u +%Y-%m-%dT%H:%MZ) from $(git rev-parse --short HEAD 2>/dev/null || echo '?')" \
    "($type build, $(uname -m), $(ldd --version | head -1 | sed 's/.* //') glibc)."
} >"$out/README"

size=$(du -sb "$out" | cut -f1)
echo "device pack: $out, $((size / 1024 / 1024)) MiB ($size bytes; limit 64 MiB with the repository)"
[ "$size" -lt "$limit" ] || { echo "device-pack.sh: the pack is over 64 MiB" >&2; exit 1; }
