# Sourced by the set-up scripts (not run): install one Debian package with apt-get, as root or
# with passwordless sudo, or give up through the caller's skip() (which says why in one line
# and exits 0, so the set-up goes on and the tests that need the package skip).
#
#   apt_install TAG PACKAGE SIZE MISSING
#     TAG      the script's name for its messages (setup_linuxcnc ...)
#     PACKAGE  the Debian package (installed without recommends, after one apt-get update)
#     SIZE     what the download costs, for the message ("about 80 MB")
#     MISSING  what is missing, the start of the skip reasons ("LinuxCNC is missing")

apt_install() {
    local tag=$1 pkg=$2 size=$3 missing=$4 log
    local as_root
    if [ "$(id -u)" -eq 0 ]; then
        as_root=()
    elif command -v sudo >/dev/null 2>&1 && sudo -n true >/dev/null 2>&1; then
        as_root=(sudo -n)
    else
        skip "$missing and installing $pkg needs root or passwordless sudo"
    fi
    command -v apt-get >/dev/null 2>&1 || skip "$missing and there is no apt-get"
    echo "$tag: installing $pkg ($size, once)" >&2
    export DEBIAN_FRONTEND=noninteractive
    log="$(mktemp)"
    if ! { "${as_root[@]}" apt-get update -qq &&
        "${as_root[@]}" apt-get install -y -qq --no-install-recommends "$pkg"; } >"$log" 2>&1; then
        tail -n 5 "$log" >&2
        rm -f "$log"
        skip "apt-get could not install $pkg"
    fi
    rm -f "$log"
}
