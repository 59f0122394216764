#!/usr/bin/env bash
# The steps of the composite action (action.yml in the repository's root), also run by .ci/run on the corpus.
#   action.sh install   a virtual environment at $IMC_VENV with the suite from $IMC_SOURCE (a folder or a wheel) and
#                       the extras $IMC_EXTRAS (comma-separated: imcpy, pyimclsts, ros); its bin/ put on $GITHUB_PATH
#   action.sh run       imc-conformance run with $IMC_ADAPTER_CMD or $IMC_ADAPTER, $IMC_SUITE, $IMC_WAIVERS, each message
#                       of $IMC_REQUIRE as --require (split as $IMC_ARGS is), and the options in $IMC_ARGS (split on
#                       any whitespace, newlines included, never by a shell; quotes and backslashes refused);
#                       JSON, JUnit and HTML reports written
#                       to $IMC_JSON, $IMC_JUNIT, $IMC_HTML; the Markdown summary appended to $GITHUB_STEP_SUMMARY when
#                       set; exits as the run did (0 pass, 1 a failure, 2 nothing could be judged) and writes that code
#                       to $GITHUB_OUTPUT as exit-code.
# Every input arrives in an environment variable: none is ever pasted into a shell command.
set -euo pipefail

# words NAME TEXT: the array NAME holds the words of TEXT, split on any whitespace (blanks, tabs, newlines: every line
# of a YAML block, not the first alone), never by a shell.
words() { IFS=$' \t\r\n' read -r -d '' -a "$1" <<< "$2" || true; }

case "${1:-}" in
install)
  python="${IMC_PYTHON:-python3}"
  "$python" -m venv "$IMC_VENV"
  target="$IMC_SOURCE"
  if [ -n "${IMC_EXTRAS:-}" ]; then target="$target[$IMC_EXTRAS]"; fi
  "$IMC_VENV/bin/python" -m pip install --quiet --disable-pip-version-check "$target"
  "$IMC_VENV/bin/imc-conformance" --version
  if [ -n "${GITHUB_PATH:-}" ]; then echo "$IMC_VENV/bin" >> "$GITHUB_PATH"; fi
  ;;
run)
  argv=(run --no-progress)
  if [ -n "${IMC_ADAPTER_CMD:-}" ]; then argv+=(--adapter-cmd "$IMC_ADAPTER_CMD"); fi
  if [ -n "${IMC_ADAPTER:-}" ]; then argv+=(--adapter "$IMC_ADAPTER"); fi
  if [ -n "${IMC_SUITE:-}" ]; then argv+=(--suite "$IMC_SUITE"); fi
  if [ -n "${IMC_WAIVERS:-}" ]; then argv+=(--waivers "$IMC_WAIVERS"); fi
  if [ -n "${IMC_REQUIRE:-}" ]; then
    words required "$IMC_REQUIRE"
    for m in ${required[@]+"${required[@]}"}; do argv+=(--require "$m"); done
  fi
  if [ -n "${IMC_ARGS:-}" ]; then
    case "$IMC_ARGS" in
    *[\"\'\\]*)
      echo "imc-conformance action: args are split on whitespace (blanks, tabs, newlines) and never by a shell, so" \
           "quotes and backslashes cannot group them: give options whose values hold no blank, quote or backslash" >&2
      if [ -n "${GITHUB_OUTPUT:-}" ]; then echo "exit-code=2" >> "$GITHUB_OUTPUT"; fi
      exit 2
      ;;
    esac
    words extra "$IMC_ARGS"
    argv+=(${extra[@]+"${extra[@]}"})
  fi
  argv+=(--json "${IMC_JSON:-conformance.json}" --junit "${IMC_JUNIT:-conformance-junit.xml}"
         --html "${IMC_HTML:-conformance.html}")
  summary=""
  if [ -n "${GITHUB_STEP_SUMMARY:-}" ]; then summary=$(mktemp); argv+=(--markdown "$summary"); fi
  code=0
  "${IMC_CONFORMANCE:-imc-conformance}" "${argv[@]}" || code=$?
  if [ -n "$summary" ] && [ -s "$summary" ]; then cat "$summary" >> "$GITHUB_STEP_SUMMARY"; fi
  if [ -n "$summary" ]; then rm -f "$summary"; fi
  if [ -n "${GITHUB_OUTPUT:-}" ]; then echo "exit-code=$code" >> "$GITHUB_OUTPUT"; fi
  exit "$code"
  ;;
*)
  echo "usage: action.sh install|run (inputs in IMC_* environment variables: see the comment at the top)" >&2
  exit 2
  ;;
esac
