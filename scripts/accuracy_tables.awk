# Turns the accuracy benchmark's results.tsv (table, row, column, run,
# exit status, r_s linear, r_s final, views used, intensity adopted, ERROR
# line) into markdown tables in the layout of the paper's tables: r_s per
# cell (linear / final, and the views used), e_s = mean |1 - r_s| per row,
# per column and
# overall, then the failure scenes and the issue's goals.
function abs(x) { return x < 0 ? -x : x }
function fmt_pair(a, b) { return sprintf("%.3f / %.3f", a, b) }
function add_key(list, count, key,    i) {
  for (i = 1; i <= count[0]; ++i) if (list[i] == key) return
  list[++count[0]] = key
}
# Prints table `t` (a pivot of rows x columns) with e_s margins.
function pivot(t, title, corner,    i, j, r, c, key, line, n, sl, sf, rn, rl, rf) {
  if (!(t in tables)) return
  print "### " title
  print ""
  line = "| " corner " |"
  for (j = 1; j <= ncols[t, 0]; ++j) line = line " " cols[t, j] " |"
  print line " e_s |"
  line = "|---|"
  for (j = 1; j <= ncols[t, 0]; ++j) line = line "---|"
  print line "---|"
  for (i = 1; i <= nrows[t, 0]; ++i) {
    r = rows[t, i]
    line = "| " r " |"
    rn = rl = rf = 0
    for (j = 1; j <= ncols[t, 0]; ++j) {
      c = cols[t, j]
      key = t SUBSEP r SUBSEP c
      if (!(key in cell)) { line = line " - |"; continue }
      line = line " " cell[key] " |"
      if (key in el) { rn++; rl += el[key]; rf += ef[key] }
    }
    print line " " (rn ? fmt_pair(rl / rn, rf / rn) : "-") " |"
    row_es[t, r] = rn ? rf / rn : -1
  }
  line = "| **e_s** |"
  n = sl = sf = 0
  for (j = 1; j <= ncols[t, 0]; ++j) {
    c = cols[t, j]
    rn = rl = rf = 0
    for (i = 1; i <= nrows[t, 0]; ++i) {
      key = t SUBSEP rows[t, i] SUBSEP c
      if (key in el) { rn++; rl += el[key]; rf += ef[key] }
    }
    line = line " " (rn ? fmt_pair(rl / rn, rf / rn) : "-") " |"
    column_es[t, c] = rn ? rf / rn : -1
    n += rn; sl += rl; sf += rf
  }
  print line " " (n ? fmt_pair(sl / n, sf / n) : "-") " |"
  print ""
}
{
  t = $1; r = $2; c = $3
  tables[t] = 1
  if (t == "failure") { failures[++nfail] = $0; next }
  if (!((t, r) in seen_row)) { seen_row[t, r] = 1; rows[t, ++nrows[t, 0]] = r }
  if (!((t, c) in seen_col)) { seen_col[t, c] = 1; cols[t, ++ncols[t, 0]] = c }
  key = t SUBSEP r SUBSEP c
  if ($5 != 0 || $6 == "-" || $7 == "-") {
    cell[key] = "refused"
    refused[++nrefused] = t ": " r ", " c ": " $10
    next
  }
  cell[key] = fmt_pair($6, $7) " (" $8 ")"
  el[key] = abs(1 - $6); ef[key] = abs(1 - $7)
  # Overall means: every scene of the per-setting tables once, and each
  # multi-aperture set's all-together run.
  if (t != "multi" || c == "all together") {
    all_n++; all_l += el[key]; all_f += ef[key]
  }
}
END {
  pivot("lens", "Table 1: r_s per scene and camera setting (clean scenes)", "scene")
  pivot("artefact", "Table 2: r_s with artefacts (50 mm f/2.8; clean reference in Table 1)", "artefact")
  pivot("multi", "Table 3: multi-aperture sets (6 poses x 3 apertures): each aperture alone vs all together", "set")
  if (nfail) {
    print "### Table 4: scenes where the method cannot work"
    print ""
    print "| scene | exit | r_s (linear / final) | what the tool said |"
    print "|---|---|---|---|"
    for (i = 1; i <= nfail; ++i) {
      split(failures[i], f, "\t")
      said = f[10] != "" ? "`" f[10] "`" : "(no error: reported a scale)"
      # A refused run reports no final scale and a linear one of 0.
      ratio = (f[6] + 0 == 0 ? "-" : sprintf("%.3f", f[6])) " / " \
              (f[7] == "-" ? "-" : sprintf("%.3f", f[7]))
      print "| " f[2] " | " f[5] " | " ratio " | " said " |"
    }
    print ""
  }
  if (nrefused) {
    print "Refused where a scale was expected:"
    for (i = 1; i <= nrefused; ++i) print "- " refused[i]
    print ""
  }
  print "### Goals"
  print ""
  if (all_n) {
    printf "- overall e_s (every scene of Tables 1-2 and each set's all-together run, %d runs): linear %.4f, final %.4f: intensity stage %s than linear on average\n", all_n, all_l / all_n, all_f / all_n, (all_f < all_l ? "better" : "NOT better")
  }
  # Settings: Table 1's columns (camera settings), Table 2's rows
  # (artefacts).
  worst = 0; worst_name = ""
  for (k in column_es) {
    split(k, parts, SUBSEP)
    if (parts[1] == "lens" && column_es[k] > worst) {
      worst = column_es[k]; worst_name = parts[2]
    }
  }
  for (k in row_es) {
    split(k, parts, SUBSEP)
    if (parts[1] == "artefact" && row_es[k] > worst) {
      worst = row_es[k]; worst_name = parts[2]
    }
  }
  printf "- per-setting e_s (final; Table 1 columns, Table 2 rows) <= 0.03: %s (worst %.4f, %s)\n", (worst <= 0.03 ? "met" : "NOT met"), worst, worst_name
  key = "multi" SUBSEP "all together"
  if (key in column_es) {
    printf "- multi-aperture e_s (final, all together) <= 0.02: %s (%.4f)\n", (column_es[key] >= 0 && column_es[key] <= 0.02 ? "met" : "NOT met"), column_es[key]
  }
  ok = 1
  for (i = 1; i <= nfail; ++i) {
    split(failures[i], f, "\t")
    if (f[5] != 1 || f[10] == "") ok = 0
  }
  if (nfail) printf "- failure scenes refused with exit 1 and an ERROR line: %s\n", (ok ? "yes" : "NO")
}
