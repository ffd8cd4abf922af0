#!/bin/sh
# A resume that is refused leaves the folder as the stopped run left it (nothing the user had
# is overwritten): the coarse supine scenario stopped at 20 ms (a checkpoint at 10 ms), then its
# regions.csv given other columns, as a folder of an earlier bagsim has. The resume exits 2
# (bad input), names the file, and every file, the INCOMPLETE marker included, is unchanged.
#   ResumeRefusedCheck.sh BAGSIM DIR SCENARIO
set -u
bagsim=$1 dir=$2 scenario=$3
rm -rf "$dir" && mkdir -p "$dir" || exit 1
fail() { echo "ResumeRefusedCheck: $*"; exit 1; }
"$bagsim" run "$scenario" --out "$dir/run" --quiet --set output.checkpoint_every=10ms \
    --set coupling.threads=1 --stop-after 0.02s
rc=$?
[ $rc -eq 130 ] || fail "the stopped run exited $rc, expected 130"
sed -i '1s/$/,extra_column/' "$dir/run/regions.csv" || exit 1
(cd "$dir/run" && md5sum * > ../before.md5) || exit 1
"$bagsim" run --resume "$dir/run" 2> "$dir/resume.err"
rc=$?
cat "$dir/resume.err"
[ $rc -eq 2 ] || fail "the refused resume exited $rc, expected 2"
grep -q "cannot resume from .*regions.csv has the columns .*the folder is left as it was" \
    "$dir/resume.err" || fail "the message does not name the file and say the folder is kept"
(cd "$dir/run" && md5sum -c --quiet ../before.md5) || fail "the refused resume changed the folder"
echo "ResumeRefusedCheck: ok"
