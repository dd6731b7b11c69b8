#!/usr/bin/env bash
# Provides GCC's Xtensa libgcc soft-float sources for build.rs and prints the
# directory that holds them (one line on stdout; messages go to stderr).
#
# Nothing from GCC is kept in this project.  The files come from Debian's
# gcc-N-source package, the source that Debian's gcc-xtensa-lx106 was built
# from (its Built-Using field), and are cached in
#   ${XT_LIBGCC_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/paperbot-lx106}/gcc-<version>-libgcc-xtensa/
# so that `cargo clean` does not trigger another download.
#
# First run (cache empty): `apt-get download gcc-12-source=<Built-Using version>`
# into a temporary directory (83 MB .deb, deleted afterwards), then stream
# libgcc/config/xtensa/{lib1funcs.S,ieee754-sf.S,ieee754-df.S,t-xtensa} out of
# the gcc tarball inside it (nothing else is written to disk).  Checks:
#   - the package version's upstream part == `xtensa-lx106-elf-gcc -dumpversion`
#   - no Debian patch shipped in the package touches those files
#   - for GCC 12.2.0: the files' SHA-256 (also checked on every cached use)
# xtensa-config.h is not fetched: build.rs uses the one that gcc-xtensa-lx106
# installs (`xtensa-lx106-elf-gcc -print-file-name=plugin`/include).
set -euo pipefail

CC=${XT_CC:-xtensa-lx106-elf-gcc}
FILES=(lib1funcs.S ieee754-sf.S ieee754-df.S t-xtensa)
# SHA-256 of gcc-12.2.0/libgcc/config/xtensa/* in gcc-12-source 12.2.0-14+deb12u1
# (usr/src/gcc-12/gcc-12.2.0-dfsg.tar.xz) -- the counts in BENCHMARKS.md are for these.
declare -A SHA256_12_2_0=(
  [lib1funcs.S]=5e501c76ae7c72bf3075629ee856e63cbded6de71c287e5a92bff0d73ceb3089
  [ieee754-sf.S]=94ef85bf059969b5ef4b34d97ba104d4ac0532b9b5045322a0ce573ac3033071
  [ieee754-df.S]=cf478fa6af966228eeaa25c72e88fb383bba7447483c58bab3905c23df40f7bd
  [t-xtensa]=3e40e5c71fd6b238084b122c03277973ad92ee7271c086f06cc95e3b664030f9
)

me=fetch-libgcc-src.sh
die() {   # die MESSAGE [WHAT-TO-DO...]
  printf '%s: error: %s\n' "$me" "$1" >&2; shift
  if (( $# )); then printf '    %s\n' "$@" >&2; fi
  exit 1
}
note() { printf '%s: %s\n' "$me" "$*" >&2; }

command -v "$CC" >/dev/null ||
  die "$CC not found." "Run: apt-get install gcc-xtensa-lx106 binutils-xtensa-lx106"
gcc_ver=$("$CC" -dumpversion)

if [[ -n ${XT_LIBGCC_CACHE:-} ]]; then root=$XT_LIBGCC_CACHE
elif [[ -n ${XDG_CACHE_HOME:-} ]]; then root=$XDG_CACHE_HOME/paperbot-lx106
elif [[ -n ${HOME:-} ]]; then root=$HOME/.cache/paperbot-lx106
else die "no cache directory: set XT_LIBGCC_CACHE, XDG_CACHE_HOME or HOME"
fi
dir=$root/gcc-$gcc_ver-libgcc-xtensa

# verify DIR: the files are there and, where pinned, have the expected SHA-256
verify() {
  local f sum
  for f in "${FILES[@]}"; do
    [[ -s $1/$f ]] || return 1
    if [[ $gcc_ver == 12.2.0 ]]; then
      sum=$(sha256sum "$1/$f") && sum=${sum%% *}
      [[ $sum == "${SHA256_12_2_0[$f]}" ]] || { note "$1/$f: SHA-256 $sum, expected ${SHA256_12_2_0[$f]}"; return 2; }
    fi
  done
}

if [[ -f $dir/SOURCE ]]; then
  rc=0; verify "$dir" || rc=$?
  if (( rc == 0 )); then printf '%s\n' "$dir"; exit 0; fi
  die "the cached GCC sources in $dir are incomplete or modified." "Run: rm -r '$dir'   and build again."
fi

# ---- fetch -------------------------------------------------------------
[[ ! -e $dir ]] || die "$dir exists but has no SOURCE file (not made by this script?)." "Run: rm -r '$dir'   and build again."
t0=$(date +%s%N)
for tool in apt-get apt-cache dpkg-query dpkg-deb tar sha256sum; do
  command -v $tool >/dev/null || die "$tool not found (this needs Debian's apt/dpkg tools; Debian bookworm)"
done
command -v xz >/dev/null || die "xz not found. Run: apt-get install xz-utils"

# gcc-xtensa-lx106 records the gcc-N source it was built from, e.g.
# "Built-Using: gcc-12 (= 12.2.0-14+deb12u1)"
built_using=$(dpkg-query -W -f='${Built-Using}' gcc-xtensa-lx106 2>/dev/null) ||
  die "Debian package gcc-xtensa-lx106 is not installed." "Run: apt-get install gcc-xtensa-lx106 binutils-xtensa-lx106"
re='(gcc-[0-9]+) \(= ([^)]+)\)'
[[ $built_using =~ $re ]] ||
  die "cannot find the gcc-N source in gcc-xtensa-lx106's Built-Using field: '$built_using'"
src=${BASH_REMATCH[1]}; want=${BASH_REMATCH[2]}
pkg=$src-source
upstream() { local v=${1#*:}; printf '%s' "${v%-*}"; }   # 1:12.2.0-14+x -> 12.2.0
[[ $(upstream "$want") == "$gcc_ver" ]] ||
  die "gcc-xtensa-lx106 was built from $src $want, but $CC -dumpversion says $gcc_ver"

# versions of $pkg that apt can download, newest first
avail=$(apt-cache madison "$pkg" 2>/dev/null | awk -F'|' '{ gsub(/ /, "", $2); print $2 }' | uniq)
[[ -n $avail ]] ||
  die "apt knows no package $pkg (needed: $pkg $want)." \
      "Run: apt-get update   (with Debian bookworm 'main' in /etc/apt/sources.list.d/ or /etc/apt/sources.list)"
if ! grep -qxF -- "$want" <<<"$avail"; then
  # The archive keeps only the newest revision.  Another Debian revision of
  # the same GCC release is accepted: the SHA-256 check below still applies.
  cand=
  while read -r v; do
    if [[ $(upstream "$v") == "$gcc_ver" ]]; then cand=$v; break; fi
  done <<<"$avail"
  [[ -n $cand ]] ||
    die "$pkg $want (what gcc-xtensa-lx106 was built from) is not available; apt offers only: $(echo $avail)." \
        "Run: apt-get update, or install the gcc-xtensa-lx106 that matches those"
  note "$pkg $want is not in the archive any more; using $cand (same GCC $gcc_ver)"
  want=$cand
fi

mkdir -p "$root" || die "cannot create the cache directory $root (set XT_LIBGCC_CACHE)"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/paperbot-lx106-gcc-src.XXXXXX")
stage=$(mktemp -d "$root/.fetch.XXXXXX")
trap 'rm -rf "$tmp" "$stage"' EXIT
# apt downloads as user _apt when run as root; let it write here
if (( EUID == 0 )) && id _apt >/dev/null 2>&1; then chown _apt "$tmp"; fi

note "fetching $pkg $want, to take libgcc/config/xtensa/{${FILES[*]}} from its gcc tarball"
(cd "$tmp" && apt-get download -q "$pkg=$want") >&2 ||
  die "'apt-get download $pkg=$want' failed (output above)." \
      "Run: apt-get update   and check that this machine reaches the Debian archive (deb.debian.org)"
debs=("$tmp"/*.deb)
[[ ${#debs[@]} == 1 && -f ${debs[0]} ]] || die "apt-get download left no single .deb in $tmp"
deb=${debs[0]}
got=$(dpkg-deb -f "$deb" Package Version | tr '\n' ' ')
[[ $got == "Package: $pkg Version: $want " ]] || die "$deb is '$got', expected $pkg $want"

# the upstream tarball, e.g. ./usr/src/gcc-12/gcc-12.2.0-dfsg.tar.xz
tarball=$(dpkg-deb --fsys-tarfile "$deb" | tar -t | grep -xE "\./usr/src/$src/gcc-${gcc_ver//./\\.}(-dfsg)?\.tar\.xz" || true)
[[ -n $tarball && $tarball != *$'\n'* ]] || die "no single gcc-$gcc_ver tarball under /usr/src/$src in $deb"
# Debian's build applies debian/patches; make sure none of them changes these files
hits=$(dpkg-deb --fsys-tarfile "$deb" | tar -xO --wildcards "./usr/src/$src/debian/patches/*" |
       grep -cE "^\+\+\+ .*libgcc/config/xtensa/(lib1funcs\.S|ieee754-[sd]f\.S|t-xtensa)" || true)
[[ $hits == 0 ]] || die "a Debian patch in $pkg $want modifies libgcc/config/xtensa; the plain tarball files would not be what Debian built"

[[ $gcc_ver == 12.2.0 ]] ||
  note "no SHA-256 recorded for GCC $gcc_ver: files not pinned (the counts in BENCHMARKS.md are for GCC 12.2.0)"
members=()
for f in "${FILES[@]}"; do members+=("gcc-$gcc_ver/libgcc/config/xtensa/$f"); done
# stream: .deb data -> gcc tarball -> only the four members
dpkg-deb --fsys-tarfile "$deb" | tar -xO "$tarball" |
  tar -xJ --no-same-owner --strip-components=4 -C "$stage" "${members[@]}" ||
  die "extracting ${members[*]} from $tarball in $deb failed"
rc=0; verify "$stage" || rc=$?
(( rc == 0 )) || die "the files extracted from $pkg $want are not the expected GCC $gcc_ver ones"
{ printf 'from: %s %s, %s\n' "$pkg" "$want" "${tarball#./}"
  printf 'files: %s\n' "${members[*]}"
  printf 'for: gcc-xtensa-lx106 %s, Built-Using: %s\n' "$(dpkg-query -W -f='${Version}' gcc-xtensa-lx106)" "$built_using"
} > "$stage/SOURCE"
chmod 755 "$stage"
# atomic: a concurrent run may have finished first
mv -T "$stage" "$dir" 2>/dev/null || { [[ -f $dir/SOURCE ]] && verify "$dir"; } ||
  die "cannot move the fetched files to $dir"
ms=$(( ($(date +%s%N) - t0) / 1000000 ))
note "$(printf 'fetched in %d.%d s into %s' $((ms / 1000)) $((ms % 1000 / 100)) "$dir")"
printf '%s\n' "$dir"
