# LLVM prints a function's literal pool (`.literal_position` and its
# `.literal` lines) before the `.section` directive that switches to the
# function's own section, so GNU as would file the literals under the
# previous function's section: literals of a flash function in IRAM, or
# out of L32R's reach ("l32r: literal target out of range"). Move each
# pool to just after the `.section` lines that follow it.
function flush() { for (i = 1; i <= n; i++) print held[i]; n = 0 }
/^[ \t]*\.literal_position/        { flush(); held[++n] = $0; in_pool = 1; next }
in_pool && /^[ \t]*\.literal[ \t]/ { held[++n] = $0; next }
in_pool && /^[ \t]*\.section[ \t]/ { print; next }
{ if (in_pool) { flush(); in_pool = 0 } print }
END { flush() }
