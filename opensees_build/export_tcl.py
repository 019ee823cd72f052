"""The exported Tcl script: header, model, recorders and the step loop with its fallback.

Layout (each part generated; scene text appears only in the header comments):

1. the audit header (:func:`.export_header.header_lines`) as ``#`` comments;
2. ``here`` / ``dataDir`` / ``outDir`` / ``writeCsv`` (the last two may be set before
   ``source``-ing the script);
3. the model and analysis commands, one per logged command (``# --- model and analysis ---``
   ... ``# --- end model ---``), support records read with ``-filePath`` from ``$dataDir``;
4. the step plan as variables and ``defineAnalysis`` (re-issued by the fallback);
5. the recorders (:mod:`.recorders`) and ``record`` at t = 0;
6. the step loop: ``analyze 1 $dt`` with every return code checked and the sub-step fallback of
   :func:`deckpound.opensees_build.engine.run_steps`, and ``trackStep`` at every converged step
   and sub-step, the engine's :func:`~deckpound.opensees_build.engine.track_step`: the gap
   closures counted as the engine counts them (printed as ``gap_closures``) and each corner's
   largest gap and its time; the first step after which a corner's seat margin
   N - (g - g(0)) is negative ends the loop with status ``unseated`` before its row is stored,
   as in the engine, and the recorder files are cut to the rows deckpound stores
   (``keepStoredRows``, :func:`.export_py.keep_stored_rows`). The status line, the unseating
   line (the engine loop's message) and the seat margins of
   :func:`.export_py.seat_margin_minima` (:func:`.export_py.seat_margin_line`) are printed.
   Optionally the loop writes deckpound's CSV: every column of the in-process result, the
   relative displacements and bent deformations derived from the support displacement records
   as :func:`.export_py.result_rows` derives them (``csvRow``, ``interpRecord``).
"""

from __future__ import annotations

from deckpound.models.file_io import csv_cell

from .export_header import ExportParts, header_lines
from .export_py import UNCHECKED_SEATS, csv_plan
from .ops import render_commands
from .quoting import comment_text, tcl_path_word, tcl_word
from .recorders import render_recorders


def _num(v) -> str:
    return repr(float(v)) if isinstance(v, float) else str(int(v))


def _tcl_list(values) -> str:
    return "{" + " ".join(_num(v) for v in values) + "}"


def _tcl_lengths(values) -> str:
    """Support lengths [m] as a Tcl list, the empty word for a seat without one."""
    return "{" + " ".join("{}" if v is None else _num(v) for v in values) + "}"


def _tcl_nested(v) -> str:
    """Nested lists of numbers as a Tcl list."""
    if isinstance(v, (list, tuple)):
        return "{" + " ".join(_tcl_nested(x) for x in v) + "}"
    return _num(v)


def _analysis_body(plan: dict) -> str:
    return "\n    ".join(
        " ".join(tcl_word(a) if isinstance(a, str) else _num(a) for a in c)
        for c in plan["analysis"]
    )


def tcl_script(p: ExportParts) -> str:
    """The complete Tcl script of ``p``: its parts, in order."""
    csv = csv_plan(p)
    return (
        tcl_prologue(p)
        + tcl_step_plan(p)
        + tcl_sampling()
        + tcl_csv_columns(csv)
        + tcl_step_loop(csv, len(p.plan["corners"]))
    )


def tcl_prologue(p: ExportParts) -> str:
    """The header comments, the folders, and the model and analysis commands."""
    head = "\n".join(f"# {comment_text(x, 'tcl')}".rstrip() for x in header_lines(p))
    body = render_commands(p.log, "tcl", file_of=p.file_of)
    return f"""{head}

set here [file dirname [file normalize [info script]]]
set dataDir [file join $here {tcl_path_word(p.data_dir)}]
if {{![info exists outDir]}} {{ set outDir [file join $here {tcl_path_word(p.out_dir)}] }}
if {{![info exists writeCsv]}} {{ set writeCsv 0 }}
file mkdir $outDir

# --- model and analysis ---
{body}# --- end model ---

"""


def tcl_step_plan(p: ExportParts) -> str:
    """The step plan as Tcl variables, ``defineAnalysis`` and the recorders."""
    plan = p.plan
    recorders = "\n".join(render_recorders(p.recorders, "tcl"))
    gap_eles = plan["gap_elements"] or [0] * len(plan["corners"])
    margin = "0.5 / $nSub" if plan["fallback"] == "substep" else "0.5"
    return f"""# step plan (tags from the legend above)
set dt {_num(plan["dt"])}
set nSteps {plan["n_steps"]}
set stride {plan["stride"]}
set fallback {tcl_word(plan["fallback"])}
set nSub {plan["substeps"]}
set bodies {_tcl_list(plan["bodies"])}
set seats {_tcl_list(plan["seats"])}
set cornerNames {{{" ".join(tcl_word(c) for c in plan["corners"])}}}
set deckCorners {_tcl_list(plan["deck_corners"])}
set seatCorners {_tcl_list(plan["seat_corners"])}
set gapEles {_tcl_list(gap_eles)}
set hasGaps {1 if plan["gap_elements"] else 0}
set g0 {_tcl_list(plan["g0"])}
set sides {_tcl_list(plan["sides"])}
set nX {_tcl_list([n[0] for n in plan["normals"]])}
set nY {_tcl_list([n[1] for n in plan["normals"]])}
set tX {_tcl_list([t[0] for t in plan["tangents"]])}
set tY {_tcl_list([t[1] for t in plan["tangents"]])}
set bentEles {_tcl_list(plan["bent_elements"])}
set friction {_tcl_list([1 if f else 0 for f in plan["corner_friction"]])}
# the support length N of the seat each corner faces [m] (empty: unseating not checked)
set seatLengths {_tcl_lengths(plan["support_lengths"])}
set seatsUnchecked {tcl_word(UNCHECKED_SEATS)}

proc defineAnalysis {{}} {{
    {_analysis_body(plan)}
}}

# --- recorders: one file per deckpound column (maps in the header) ---
# -dT = (stride - half a sub-step) * dt: one row per output step, none from sub-steps
set recDT [expr {{($stride - {margin}) * $dt}}]
{recorders}
set recorderFiles [list {" ".join(tcl_word(r.file) for r in p.recorders)}]
# --- end recorders ---

"""


def tcl_sampling() -> str:
    """``cornerGaps`` and ``sampleRow``: the engine's :func:`~.engine.sample_row` in Tcl."""
    return """# deckpound's CSV (writeCsv 1): the engine's sample_row, in Tcl
proc cornerGaps {} {
    global deckCorners seatCorners g0 nX nY
    set out {}
    for {set c 0} {$c < [llength $g0]} {incr c} {
        set dk [lindex $deckCorners $c]
        set st [lindex $seatCorners $c]
        set g [expr {[lindex $g0 $c] + [lindex $nX $c] * ([nodeDisp $dk 1] - [nodeDisp $st 1])}]
        if {[lindex $nY $c] != 0.0} {
            set g [expr {$g + [lindex $nY $c] * ([nodeDisp $dk 2] - [nodeDisp $st 2])}]
        }
        lappend out $g
    }
    return $out
}

proc sampleRow {t} {
    global bodies seats gapEles hasGaps friction nX nY tX tY bentEles g0
    set s1 [nodeDisp [lindex $seats 0]]
    set s2 [nodeDisp [lindex $seats 1]]
    set v1 [nodeVel [lindex $seats 0]]
    set v2 [nodeVel [lindex $seats 1]]
    set row [list $t]
    foreach body $bodies {
        set dk [nodeDisp $body]
        lappend row [lindex $dk 0] [lindex $dk 1] [lindex $dk 2]
    }
    lappend row [lindex $s1 0] [lindex $s1 2] [lindex $s2 0] [lindex $s2 2]
    foreach body $bodies {
        set vk [nodeVel $body]
        lappend row [lindex $vk 0] [lindex $vk 1] [lindex $vk 2]
    }
    lappend row [lindex $v1 0] [lindex $v1 2] [lindex $v2 0] [lindex $v2 2]
    set row [concat $row [cornerGaps]]
    set fn {}
    set ft {}
    for {set c 0} {$c < [llength $g0]} {incr c} {
        set e [lindex $gapEles $c]
        if {!$hasGaps} {
            lappend fn 0.0; lappend ft 0.0
        } elseif {[lindex $friction $c]} {
            set f [eleResponse $e force]
            set fx [lindex $f 3]
            set fy [lindex $f 4]
            lappend fn [expr {-([lindex $nX $c] * $fx + [lindex $nY $c] * $fy) + 0.0}]
            lappend ft [expr {-([lindex $tX $c] * $fx + [lindex $tY $c] * $fy) + 0.0}]
        } else {
            lappend fn [expr {-[lindex [eleResponse $e basicForce] 0]}]
            lappend ft 0.0
        }
    }
    set row [concat $row $fn $ft]
    foreach e $bentEles {
        set f [eleResponse $e basicForce]
        lappend row [lindex $f 0] [lindex $f 1]
    }
    return $row
}

"""


def tcl_csv_columns(csv: dict) -> str:
    """The CSV's derived columns (:func:`.export_py.csv_plan` ``csv``): the support
    records, ``interpRecord`` and ``csvRow``."""
    records = " ".join(tcl_word(f) for f in csv["records"])
    return f"""# the CSV's derived columns (export_py.result_rows): support displacement records read from
# $dataDir, interpolated as np.interp at each row's time; the deck relative to the mean of its
# tables, each seat relative to its actuator, each bent spring's d = B u - S u_g
set relDt {_num(csv["dt"])}
set relRecordFiles [list {records}]
set relMeans {_tcl_nested(csv["means"])}
set relSeats {_tcl_nested(csv["seats"])}
set relSprings {_tcl_nested(csv["springs"])}
set relOrder {_tcl_list(csv["order"])}

proc readRecord {{name}} {{
    global dataDir
    set fh [open [file join $dataDir $name] r]
    set values {{}}
    foreach line [split [read $fh] "\n"] {{
        if {{[string trim $line] ne ""}} {{ lappend values [expr {{double($line)}}] }}
    }}
    close $fh
    return $values
}}

proc interpRecord {{values dt t}} {{
    set last [expr {{[llength $values] - 1}}]
    if {{$t >= $last * $dt}} {{ return [lindex $values $last] }}
    if {{$t <= 0.0}} {{ return [lindex $values 0] }}
    set j [expr {{int($t / $dt)}}]
    while {{$j > 0 && $j * $dt > $t}} {{ incr j -1 }}
    while {{($j + 1) * $dt <= $t}} {{ incr j }}
    set y0 [lindex $values $j]
    if {{$j * $dt == $t}} {{ return $y0 }}
    set y1 [lindex $values [expr {{$j + 1}}]]
    set slope [expr {{($y1 - $y0) / (($j + 1) * $dt - $j * $dt)}}]
    return [expr {{$slope * ($t - $j * $dt) + $y0}}]
}}

proc total {{terms}} {{
    set out [lindex $terms 0]
    foreach x [lrange $terms 1 end] {{ set out [expr {{$out + $x}}] }}
    return $out
}}

proc csvRow {{row}} {{
    global relDt relRecords relMeans relSeats relSprings relOrder
    set t [lindex $row 0]
    set ug {{}}
    foreach values $relRecords {{ lappend ug [interpRecord $values $relDt $t] }}
    set full $row
    foreach item $relMeans {{
        lassign $item col chans
        set mean 0.0
        if {{[llength $chans]}} {{
            set terms {{}}
            foreach k $chans {{ lappend terms [lindex $ug $k] }}
            set mean [expr {{[total $terms] / double([llength $chans])}}]
        }}
        lappend full [expr {{[lindex $row $col] - $mean}}]
    }}
    foreach item $relSeats {{
        lassign $item col ch
        lappend full [expr {{[lindex $row $col] - [lindex $ug $ch]}}]
    }}
    foreach spring $relSprings {{
        lassign $spring dofs chans
        set bu {{}}
        foreach term $dofs {{ lappend bu [expr {{[lindex $row [lindex $term 0]] * [lindex $term 1]}}] }}
        set sg {{}}
        foreach term $chans {{ lappend sg [expr {{[lindex $ug [lindex $term 0]] * [lindex $term 1]}}] }}
        lappend full [expr {{[total $bu] - [total $sg]}}]
    }}
    set out {{}}
    foreach i $relOrder {{ lappend out [lindex $full $i] }}
    return [join $out ","]
}}

"""


def tcl_step_loop(csv: dict, nc: int) -> str:
    """``trackStep`` (the engine's :func:`~.engine.track_step`: gap closures and seat
    margins), ``keepStoredRows`` and the step loop with the sub-step fallback and the
    unseating stop of :func:`deckpound.opensees_build.engine.run_steps`, writing the CSV's
    rows, then the status, unseating and seat-margin lines; ``nc`` corners."""
    columns = " ".join(tcl_word(csv_cell(c)) for c in csv["header"])
    zeros = " ".join(["0"] * nc)
    return f"""# every converged step and sub-step, as the engine's track_step: the gap closures (deckpound's
# one definition: a corner is in contact when its gap is <= 0 or its normal force > 0; a closure
# is a step at which a corner goes from out of contact to in contact, in contact at t = 0: one)
# and each corner's largest gap g_max and its time (the first call gives g(0)): the corner is
# unseated at the first step at which g_max - g(0) exceeds the support length N of the seat it
# faces, seat margin N - (g - g(0)) < 0
set inside {{{zeros}}}
set gapClosures 0
set gapOpen {{{" ".join(["-Inf"] * nc)}}}
set gapOpenTime {{{" ".join(["0.0"] * nc)}}}
set gapStart {{{" ".join(["0.0"] * nc)}}}
set unseated {{}}
proc trackStep {{t}} {{
    global inside gapClosures hasGaps gapEles friction nX nY cornerNames
    global seatLengths gapOpen gapOpenTime gapStart unseated
    set gaps [cornerGaps]
    for {{set c 0}} {{$c < [llength $gaps]}} {{incr c}} {{
        set g [lindex $gaps $c]
        if {{$hasGaps}} {{
            set now [expr {{$g <= 0.0}}]
            if {{!$now}} {{
                set e [lindex $gapEles $c]
                if {{[lindex $friction $c]}} {{
                    set f [eleResponse $e force]
                    set fn [expr {{-([lindex $nX $c] * [lindex $f 3] + [lindex $nY $c] * [lindex $f 4])}}]
                }} else {{
                    set fn [expr {{-[lindex [eleResponse $e basicForce] 0]}}]
                }}
                set now [expr {{$fn > 0.0}}]
            }}
            if {{$now && ![lindex $inside $c]}} {{ incr gapClosures }}
            lset inside $c $now
        }}
        if {{$g > [lindex $gapOpen $c]}} {{
            if {{[lindex $gapOpen $c] == -Inf}} {{ lset gapStart $c $g }}
            lset gapOpen $c $g
            lset gapOpenTime $c $t
            set support [lindex $seatLengths $c]
            if {{$support ne "" && $unseated eq ""}} {{
                if {{$g - [lindex $gapStart $c] > $support}} {{
                    set unseated [list [lindex $cornerNames $c] $t]
                }}
            }}
        }}
    }}
}}

# the recorder files keep the rows deckpound stores: OpenSees recorded the commit of the
# unseating step when it was an output step, the engine keeps no row of that step
proc keepStoredRows {{nRows}} {{
    global outDir recorderFiles
    foreach name $recorderFiles {{
        set path [file join $outDir $name]
        set fh [open $path r]
        set lines [split [read -nonewline $fh] "\\n"]
        close $fh
        if {{[llength $lines] > $nRows}} {{
            set fh [open $path w]
            puts $fh [join [lrange $lines 0 [expr {{$nRows - 1}}]] "\\n"]
            close $fh
        }}
    }}
}}

# --- step loop (deckpound's run_steps): every analyze checked, sub-step fallback, unseating ---
record
trackStep 0.0
if {{$writeCsv}} {{
    set relRecords {{}}
    foreach name $relRecordFiles {{ lappend relRecords [readRecord $name] }}
    set fh [open [file join $outDir opensees.csv] w]
    puts $fh [join [list {columns}] ","]
    puts $fh [csvRow [sampleRow 0.0]]
}}
set failures 0
set rescued 0
set status success
set steps 0
set storedRows 1
for {{set n 1}} {{$n <= $nSteps}} {{incr n}} {{
    set ok [analyze 1 $dt]
    if {{$ok == 0}} {{ trackStep [expr {{$n * $dt}}] }}
    if {{$ok != 0}} {{
        incr failures
        puts "step $n (t = [expr {{$n * $dt}}] s) failed with code $ok"
        if {{$fallback == "substep"}} {{
            wipeAnalysis
            defineAnalysis
            set h [expr {{$dt / $nSub}}]
            for {{set k 0}} {{$k < $nSub}} {{incr k}} {{
                set ok [analyze 1 $h]
                if {{$ok != 0}} {{ break }}
                if {{$k == $nSub - 1}} {{
                    trackStep [expr {{$n * $dt}}]
                }} else {{
                    trackStep [expr {{($n - 1) * $dt + ($k + 1) * $h}}]
                }}
            }}
            wipeAnalysis
            defineAnalysis
            if {{$ok == 0}} {{ incr rescued }}
        }}
    }}
    if {{$ok != 0}} {{
        set status failed
        puts "step $n (t = [expr {{$n * $dt}}] s) did not converge"
        break
    }}
    set steps $n
    if {{$unseated ne ""}} {{
        set status unseated
        break
    }}
    if {{$n % $stride == 0}} {{
        incr storedRows
        if {{$writeCsv}} {{ puts $fh [csvRow [sampleRow [expr {{$n * $dt}}]]] }}
    }}
}}
if {{$writeCsv}} {{ close $fh }}
wipe
if {{$status == "unseated"}} {{ keepStoredRows $storedRows }}
puts "$status, failures: $failures, rescued by sub-steps: $rescued, gap_closures: $gapClosures"
if {{$status == "unseated"}} {{
    lassign $unseated corner when
    puts "corner $corner unseated at t = [format %.6g $when] s (step $steps)"
}}
# the seat margins N - (g_max - g(0)) [m] at the time of the largest gap [s], the engine's
# (export_py.seat_margin_minima)
set margins {{}}
for {{set c 0}} {{$c < [llength $seatLengths]}} {{incr c}} {{
    set support [lindex $seatLengths $c]
    if {{$support ne ""}} {{
        set opening [expr {{[lindex $gapOpen $c] - [lindex $gapStart $c]}}]
        lappend margins "[lindex $cornerNames $c] [expr {{$support - $opening}}] [lindex $gapOpenTime $c]"
    }}
}}
if {{[llength $margins]}} {{
    puts "seat_margin_min (margin m, time s): [join $margins {{, }}]"
}} else {{
    puts "seat_margin_min: $seatsUnchecked"
}}
if {{$status ni {{success unseated}}}} {{ exit 1 }}
"""
