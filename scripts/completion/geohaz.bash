# bash completion for the geohaz apps (sph-slope, debris-runout, dem-avalanche, slope-stability, geohaz-report,
# geohaz-ensemble).
# Installed as share/bash-completion/completions/<app>; to try it from a source tree:
#   source scripts/completion/geohaz.bash
# Options come from the app's own --help and config keys (after --set) from its --help-config, so
# the completion never disagrees with the app it completes.

_geohaz_complete() {
  local app=$1 cur prev
  cur=${COMP_WORDS[COMP_CWORD]}
  prev=${COMP_WORDS[COMP_CWORD - 1]}
  local exe=${COMP_WORDS[0]}
  case $prev in
    --config | -c)
      mapfile -t COMPREPLY < <(compgen -f -X '!*.toml' -- "$cur"; compgen -d -- "$cur")
      return ;;
    --out | -o | --results)
      mapfile -t COMPREPLY < <(compgen -d -- "$cur")
      return ;;
    --release | --release-from | --dsm | --make-synthetic-dsm)
      mapfile -t COMPREPLY < <(compgen -f -- "$cur")
      return ;;
    --threads | -j)
      mapfile -t COMPREPLY < <(compgen -W "0 1 2 4 8" -- "$cur")
      return ;;
    --friction)
      mapfile -t COMPREPLY < <(compgen -W "manning voellmy coulomb" -- "$cur")
      return ;;
    --set)
      # Config keys, completed up to the '='.
      local keys
      # (a key of an array of tables, "material[].cohesion", is offered for the first entry,
      # "material[0].cohesion", the form --set takes)
      keys=$("$exe" --help-config 2>/dev/null | sed -n 's/^\([a-z_][][a-z0-9_.]*\)  (.*/\1=/p' | sed 's/\[\]/[0]/g')
      compopt -o nospace 2>/dev/null
      mapfile -t COMPREPLY < <(compgen -W "$keys" -- "$cur")
      return ;;
  esac
  if [[ $cur == -* ]]; then
    local opts
    opts=$("$exe" --help 2>/dev/null | grep -o -- '--[a-z][a-z0-9-]*' | sort -u)
    mapfile -t COMPREPLY < <(compgen -W "$opts" -- "$cur")
    return
  fi
  # Positional arguments (debris-runout's DSM) and anything else: files.
  mapfile -t COMPREPLY < <(compgen -f -- "$cur")
}

complete -o filenames -F _geohaz_complete sph-slope debris-runout dem-avalanche geohaz-report geohaz-ensemble geohaz-calibrate slope-stability
