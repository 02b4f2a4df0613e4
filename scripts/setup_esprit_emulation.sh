#!/usr/bin/env bash
# Build the .NET ESPRIT emulation the adapter tests load through pythonnet:
#   adapters/esprit_com/csharp/EspritEmulation.cs -> adapters/esprit_com/build/EspritEmulation.dll
#
# Installs Mono (Debian's mono-devel: mcs and the netstandard facade pythonnet needs) with
# apt-get only when mcs is missing and we are root or have passwordless sudo. Where Mono cannot
# be had it says so in one line and exits 0: the set-up goes on and the .NET emulation tests
# skip with that reason. Idempotent: recompiles only when the source is newer than the DLL.
set -uo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
src="$root/adapters/esprit_com/csharp/EspritEmulation.cs"
out_dir="$root/adapters/esprit_com/build"
dll="$out_dir/EspritEmulation.dll"

skip() {
    echo "setup_esprit_emulation: $1; the .NET ESPRIT emulation tests will be skipped" >&2
    exit 0
}

if ! command -v mcs >/dev/null 2>&1; then
    . "$root/scripts/apt_install.sh"
    apt_install setup_esprit_emulation mono-devel "about 330 MB" "Mono's mcs is missing"
    command -v mcs >/dev/null 2>&1 || skip "mono-devel is installed but mcs is not on PATH"
fi

if [ -f "$dll" ] && [ "$dll" -nt "$src" ]; then
    exit 0
fi
mkdir -p "$out_dir" || skip "cannot create $out_dir"
# Compile beside the target and rename, so a failed build never leaves a half-written DLL.
tmp="$out_dir/.EspritEmulation.dll.part"
if ! mcs -nologo -target:library -warnaserror+ -out:"$tmp" "$src"; then
    rm -f "$tmp"
    echo "setup_esprit_emulation: mcs failed on $src" >&2
    exit 1
fi
mv -f "$tmp" "$dll"
echo "setup_esprit_emulation: built $dll" >&2
