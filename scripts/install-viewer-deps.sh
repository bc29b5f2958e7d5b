#!/usr/bin/env bash
# Installs what the browser viewer needs, only what is missing:
#   - Debian: libcpp-httplib-dev (`semap view`'s server), nodejs + npm (bundling three.js at
#     build time), chromium (the headless viewer test);
#   - npm: viewer/node_modules from the committed package-lock.json (three, esbuild,
#     playwright-core; playwright never downloads browsers, the test uses /usr/bin/chromium).
# Idempotent and quiet when everything is already there.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(libcpp-httplib-dev nodejs npm chromium)
missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    # node/npm may come from elsewhere (nodesource, nvm): a working binary is enough.
    case "$p" in
      nodejs) command -v node >/dev/null && continue ;;
      npm) command -v npm >/dev/null && continue ;;
    esac
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  echo "semap: installing viewer packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if [ ! -f viewer/node_modules/three/package.json ] || [ ! -f viewer/node_modules/esbuild/package.json ] ||
   [ ! -f viewer/node_modules/playwright-core/package.json ]; then
  echo "semap: npm ci in viewer/"
  (cd viewer && PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund)
fi
