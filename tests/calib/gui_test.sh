#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The interactive colour-table trainer (cyl-train --gui) under a headless X server: scripted
# mouse drags and keys (xdotool), screenshots of the X screen (ImageMagick's import) checked
# pixel by pixel, and the saved table checked byte by byte.
#   tests/calib/gui_test.sh BUILD_DIR
# Needs Debian's xvfb, xdotool and imagemagick (mk/calib.mk installs them). Prints GoogleTest-style
# "[  PASSED  ] N tests." / "[  FAILED  ] N tests." lines; fails loudly if it cannot run.
set -u
BUILD=${1:-build}
TOOL=$BUILD/cyl-train
CONVERT=/usr/bin/convert   # ImageMagick's (a stand-in may shadow `convert` on PATH)
IMPORT=/usr/bin/import
pass=0
fail=0
ok() { echo "[       OK ] $1"; pass=$((pass + 1)); }
bad() { echo "[  FAILED  ] $1: $2"; fail=$((fail + 1)); }
finish() {
  echo "[  PASSED  ] $pass tests."
  [ $fail -gt 0 ] && echo "[  FAILED  ] $fail tests."
  [ $fail -eq 0 ]
  exit $?
}
for t in Xvfb xdotool "$IMPORT" "$CONVERT" "$TOOL"; do
  if ! command -v "$t" >/dev/null; then bad setup "missing $t"; finish; fi
done

W=$(mktemp -d /tmp/cyl_gui_test.XXXXXX)
XPID=""
TPID=""
cleanup() {
  # CYL_GUI_TEST_KEEP=DIR keeps the screenshots for a look
  [ -n "${CYL_GUI_TEST_KEEP:-}" ] && mkdir -p "$CYL_GUI_TEST_KEEP" && cp "$W"/*.png "$CYL_GUI_TEST_KEEP"/ 2>/dev/null
  [ -n "$TPID" ] && kill "$TPID" 2>/dev/null
  [ -n "$XPID" ] && kill "$XPID" 2>/dev/null
  rm -rf "$W"
}
trap cleanup EXIT

# The X server picks a free display itself (-displayfd: no race with another server choosing the
# same number) and does not reset when its last client disconnects (-noreset: the readiness probe
# below is a client; a reset between it and the tool's connection refused the tool once in CI).
Xvfb -displayfd 3 -noreset -screen 0 800x600x24 -nolisten tcp 3>"$W/display" >"$W/xvfb.log" 2>&1 &
XPID=$!
D=""
for i in $(seq 100); do
  D=$(head -1 "$W/display" 2>/dev/null)
  [ -n "$D" ] && break
  kill -0 "$XPID" 2>/dev/null || break
  sleep 0.1
done
[ -z "$D" ] && { bad setup "Xvfb gave no display: $(cat "$W/xvfb.log")"; finish; }
export DISPLAY=:$D
for i in $(seq 50); do xdotool getmouselocation >/dev/null 2>&1 && break; sleep 0.1; done
xdotool getmouselocation >/dev/null 2>&1 || { bad setup "Xvfb did not start: $(cat "$W/xvfb.log")"; finish; }
xstate() { if kill -0 "$XPID" 2>/dev/null; then echo "X server :$D running"; else echo "X server :$D gone: $(cat "$W/xvfb.log")"; fi; }

# test image: grey, an orange patch (x 40..99, y 60..159) and a green one (x 200..249, y 80..169)
"$CONVERT" -size 320x240 xc:'rgb(120,120,120)' -fill 'rgb(240,120,20)' -draw 'rectangle 40,60 99,159' \
  -fill 'rgb(40,170,60)' -draw 'rectangle 200,80 249,169' "$W/patches.png"

"$TOOL" --gui "$W/patches.png" -o "$W/out.cylt" --class orange --color 255,0,255 --snapshot "$W/snap.png" \
  >"$W/tool.log" 2>&1 &
TPID=$!
wid=""
for i in $(seq 100); do
  wid=$(xdotool search --name '^cyl-train$' 2>/dev/null | head -1)
  [ -n "$wid" ] && grep -q "window open" "$W/tool.log" && break
  sleep 0.1
done
if [ -z "$wid" ]; then bad window "no cyl-train window: $(cat "$W/tool.log"); $(xstate)"; finish; fi
ok "window opens"
sleep 0.5
eval "$(xdotool getwindowgeometry --shell "$wid")"   # X Y WIDTH HEIGHT of the window
# the image is at the window's origin, the status bar (54 px) below it
if [ "$WIDTH" -eq 320 ] && [ "$HEIGHT" -eq 294 ]; then ok "window is the image plus the status bar"; else
  bad geometry "window ${WIDTH}x${HEIGHT}, expected 320x294"; fi
xdotool windowfocus --sync "$wid" 2>/dev/null || xdotool windowfocus "$wid"

pixel() {  # pixel FILE x y -> "r g b"
  "$CONVERT" "$1" -format "%[fx:int(255*p{$2,$3}.r)] %[fx:int(255*p{$2,$3}.g)] %[fx:int(255*p{$2,$3}.b)]" info:
}
shot() { "$IMPORT" -window root "$W/$1"; }
drag() {  # drag x0 y0 x1 y1 (image coordinates)
  xdotool mousemove --sync $((X + $1)) $((Y + $2)); sleep 0.1
  xdotool mousedown 1; sleep 0.1
  xdotool mousemove --sync $((X + ($1 + $3) / 2)) $((Y + ($2 + $4) / 2)); sleep 0.1
  xdotool mousemove --sync $((X + $3)) $((Y + $4)); sleep 0.1
  xdotool mouseup 1; sleep 0.1
}
wait_log() {  # wait_log PATTERN COUNT
  for i in $(seq 50); do
    [ "$(grep -c "$1" "$W/tool.log")" -ge "$2" ] && return 0
    sleep 0.1
  done
  return 1
}
key() { xdotool key --delay 50 "$@"; sleep 0.3; }

shot before.png
read -r r0 g0 b0 <<<"$(pixel "$W/before.png" $((X + 70)) $((Y + 110)))"
# 1. drag over the orange patch: trained, and the overlay turns it magenta
drag 50 70 90 150
if wait_log "trained orange" 1; then ok "drag trains the class"; else bad drag "no training: $(cat "$W/tool.log")"; fi
sleep 0.4
shot trained.png
read -r r1 g1 b1 <<<"$(pixel "$W/trained.png" $((X + 70)) $((Y + 110)))"
read -r rg gg bg <<<"$(pixel "$W/trained.png" $((X + 225)) $((Y + 120)))"
read -r rb gb bb <<<"$(pixel "$W/trained.png" $((X + 10)) $((Y + 10)))"
if [ "$b1" -gt $((b0 + 80)) ] && [ "$g1" -lt $((g0 - 40)) ] && [ "$r1" -gt 200 ]; then
  ok "overlay shows the class colour on the landmark (before $r0,$g0,$b0 after $r1,$g1,$b1)"
else bad overlay "landmark pixel before $r0,$g0,$b0 after $r1,$g1,$b1"; fi
if [ "$gg" -gt "$rg" ] && [ "$gg" -gt "$bg" ] && [ "$rb" -lt 150 ] && [ "$bb" -lt 150 ] && [ "$((rb - bb))" -lt 20 ]; then
  ok "green patch and background stay unclassified"
else bad overlay2 "green $rg,$gg,$bg background $rb,$gb,$bb"; fi
# 2. undo: the overlay goes away
key u
shot undone.png
read -r r2 g2 b2 <<<"$(pixel "$W/undone.png" $((X + 70)) $((Y + 110)))"
if [ "$b2" -lt $((b0 + 20)) ] && [ "$g2" -gt $((g0 - 20)) ]; then ok "undo removes the training ($r2,$g2,$b2)"; else
  bad undo "landmark pixel after undo $r2,$g2,$b2"; fi
# 3. train again, rename the class, save, snapshot, quit
drag 45 65 95 155
wait_log "trained orange" 2 || bad drag2 "second drag not trained"
key r c o n e Return
key s
if wait_log "saved" 1; then ok "s saves the table"; else bad save "no save: $(cat "$W/tool.log")"; fi
key p
wait_log "wrote" 1 || true
key q
for i in $(seq 50); do kill -0 "$TPID" 2>/dev/null || break; sleep 0.1; done
if kill -0 "$TPID" 2>/dev/null; then bad quit "q did not quit"; else ok "q quits"; wait "$TPID"; rc=$?; TPID="";
  [ $rc -eq 0 ] && ok "exit code 0" || bad exitcode "exit $rc"; fi
# the table: CYLT magic, class 0 named "cone" with display colour 255,0,255 (offsets: colortable.h)
if [ -f "$W/out.cylt" ] && [ "$(stat -c %s "$W/out.cylt")" -eq 65964 ] && [ "$(head -c 4 "$W/out.cylt")" = CYLT ] &&
   [ "$(dd if="$W/out.cylt" bs=1 skip=8 count=4 2>/dev/null)" = cone ] &&
   [ "$(od -An -tu1 -j24 -N3 "$W/out.cylt" | tr -s ' ')" = " 255 0 255" ]; then
  ok "saved table: class 0 'cone', magenta"
else bad table "table missing or wrong: $(od -c -N40 "$W/out.cylt" 2>&1 | head -3)"; fi
# the window snapshot (key p) shows the trained landmark too
if [ -f "$W/snap.png" ]; then
  read -r r3 g3 b3 <<<"$(pixel "$W/snap.png" 70 110)"
  if [ "$b3" -gt $((b0 + 80)) ] && [ "$g3" -lt $((g0 - 40)) ]; then ok "snapshot shows the overlay"; else
    bad snapshot "snapshot pixel $r3,$g3,$b3"; fi
else bad snapshot "no snapshot written"; fi
ls "$W" | grep -q '\.tmp\.' && bad tmpfiles "temporary files left: $(ls "$W")"
# 4. learn mode: a box dragged is a labelled example; the classes are learned from it (report on
# stdout and in the status line), s saves a version-2 table and the box as a YOLO label beside
# the image; --learn loads the labels again
cp "$W/patches.png" "$W/learn.png"
"$TOOL" --gui "$W/learn.png" --learn -o "$W/learned.cylt" --class orange >"$W/tool.log" 2>&1 &
TPID=$!
wid=""
for i in $(seq 100); do
  wid=$(xdotool search --name '^cyl-train$' 2>/dev/null | head -1)
  [ -n "$wid" ] && grep -q "window open" "$W/tool.log" && break
  sleep 0.1
done
if [ -z "$wid" ]; then bad learnwindow "no window: $(cat "$W/tool.log"); $(xstate)"; finish; fi
sleep 0.5
eval "$(xdotool getwindowgeometry --shell "$wid")"
xdotool windowfocus --sync "$wid" 2>/dev/null || xdotool windowfocus "$wid"
drag 40 60 99 159
if wait_log "^orange " 1; then ok "learn mode: a box learns the class (report printed)"; else
  bad learn "no report: $(cat "$W/tool.log")"; fi
key s
wait_log "saved .*learn.txt" 1 || bad learnsave "labels not saved: $(cat "$W/tool.log")"
key q
for i in $(seq 50); do kill -0 "$TPID" 2>/dev/null || break; sleep 0.1; done
kill -0 "$TPID" 2>/dev/null && kill "$TPID"; TPID=""
# the box (40..99 x 60..159 inclusive drag corners -> [40, 100) x [60, 160)) in a 320x240 image
if [ "$(cat "$W/learn.txt" 2>/dev/null)" = "0 0.218750 0.458333 0.187500 0.416667" ]; then ok "labels saved as YOLO beside the image"
else bad labels "learn.txt: $(cat "$W/learn.txt" 2>&1)"; fi
if [ "$(stat -c %s "$W/learned.cylt" 2>/dev/null)" = 197036 ] &&
   "$BUILD/cyl-score" -q --table "$W/learned.cylt" --class orange=0 "$W/learn.png" | tail -1 |
   grep -q '"recall_iou50": 1.0000'; then
  ok "the learned table finds the labelled patch (version 2, cyl-score recall 1)"
else bad learned "table: $(ls -la "$W/learned.cylt" 2>&1)"; fi

# 5. headless without a display: a clear error, exit 1
out=$(env -u DISPLAY "$TOOL" --gui "$W/patches.png" -o "$W/x.cylt" 2>&1); rc=$?
if [ $rc -eq 1 ] && echo "$out" | grep -q DISPLAY && [ ! -e "$W/x.cylt" ]; then ok "no display: clear error"; else
  bad nodisplay "exit $rc: $out"; fi
finish
