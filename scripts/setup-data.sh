#!/usr/bin/env bash
# Installs, with apt-get, only what scripts/fetch-data needs and is missing, and makes apt's
# package lists know the Debian packages fetch-data downloads. Idempotent; prints nothing
# when everything is present. Run as root (or with sudo available).
#
#   python3 python3-venv   a Python with venv + ensurepip, for the conversion tools' venv
#                          (skipped when the python3 on PATH already has both)
#   ca-certificates        HTTPS to PyPI
#   bsdextrautils          'column', for the summary table (optional; cat otherwise)
# apt-get, apt-cache, dpkg-deb, tar, sha256sum and flock are part of every Debian system.
set -euo pipefail

packages=(ca-certificates bsdextrautils)
if ! python3 -c 'import venv, ensurepip' >/dev/null 2>&1; then
  packages+=(python3 python3-venv)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ "$(id -u)" -eq 0 ]; then sudo=(); else sudo=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
updated=0
# fetch-data runs 'apt-get download mricron-data blender-data': the lists must know them.
if ((${#missing[@]})) || ! apt-cache show mricron-data blender-data >/dev/null 2>&1; then
  "${sudo[@]}" apt-get update -qq
  updated=1
fi
if ((${#missing[@]})); then
  echo "setup-data: installing ${missing[*]}" >&2
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
if ((updated)) && ! apt-cache show mricron-data blender-data >/dev/null 2>&1; then
  echo "setup-data: apt knows no mricron-data / blender-data even after 'apt-get update';" \
       "add Debian bookworm's main archive to the apt sources" >&2
  exit 1
fi
