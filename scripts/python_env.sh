# The Python environment of the check scripts (sourced by check.sh and results.sh; ROOT is the
# repository): creates .venv at ROOT if missing and installs scripts/requirements.txt into it,
# skipped when the requirements file is unchanged since the last install or when pip freeze
# already satisfies every pin. Sets VENV, PY and REQ.
VENV="$ROOT/.venv"
PY="$VENV/bin/python"
REQ="$ROOT/scripts/requirements.txt"
STAMP="$VENV/.req-hash"

if [[ ! -x "$PY" ]]; then
    step "creating $VENV"
    python3 -m venv "$VENV"
fi

req_hash=$(sha256sum "$REQ" | cut -d' ' -f1)

# True if every 'name==version' pin of requirements.txt appears in pip freeze.
freeze_satisfies() {
    local frozen
    frozen=$("$PY" -m pip freeze 2>/dev/null | tr '[:upper:]_' '[:lower:]-')
    local pin
    while read -r pin; do
        pin=${pin%%#*}
        pin=$(echo "$pin" | tr -d '[:space:]' | tr '[:upper:]_' '[:lower:]-')
        [[ -z "$pin" ]] && continue
        grep -qxF "$pin" <<<"$frozen" || return 1
    done <"$REQ"
}

if [[ -f "$STAMP" && "$(cat "$STAMP")" == "$req_hash" ]]; then
    echo "== python requirements unchanged (hash in $STAMP)"
elif freeze_satisfies; then
    echo "== python requirements already satisfied"
    echo "$req_hash" >"$STAMP"
else
    step "installing python requirements"
    "$PY" -m pip install --quiet --disable-pip-version-check -r "$REQ"
    echo "$req_hash" >"$STAMP"
fi

