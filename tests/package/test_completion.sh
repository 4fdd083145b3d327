#!/usr/bin/env bash
# ctest package_completion: the bash completion (scripts/completion/geohaz.bash) completes the apps'
# options, choices and config keys from the built apps.
#   test_completion.sh <source dir> <build dir>
set -uo pipefail
src=$1
build=$2
source "$src/scripts/completion/geohaz.bash"
compopt() { :; }  # only available inside a real completion
fails=0
expect() {  # expect "<words>" "<reply>"
  read -r -a COMP_WORDS <<<"$1"
  COMP_CWORD=$((${#COMP_WORDS[@]} - 1))
  COMPREPLY=()
  _geohaz_complete "$(basename "${COMP_WORDS[0]}")"
  if [ "${COMPREPLY[*]}" != "$2" ]; then
    echo "FAILED: '$1' → '${COMPREPLY[*]}', expected '$2'"
    fails=$((fails + 1))
  else
    echo "ok: '$1' → '$2'"
  fi
}
runout=$build/apps/debris-runout/debris-runout
sph=$build/apps/sph-slope/sph-slope
dem=$build/apps/dem-avalanche/dem-avalanche
ens=$build/apps/geohaz-ensemble/geohaz-ensemble
expect "$runout --fri" "--friction"
expect "$runout --release-f" "--release-from"
expect "$runout --friction v" "voellmy"
expect "$runout --set model.fri" "model.friction="
expect "$sph --set material[0].coh" "material[0].cohesion="
expect "$sph --help-c" "--help-config"
expect "$dem --set bond.tensile_strength_" "bond.tensile_strength_std="
expect "$dem --threads 1" "1"
[ -x "$ens" ] && expect "$ens --set ensemble.samp" "ensemble.sampling="
[ $fails -eq 0 ]
