"""The fuzz classifier: what a case's command or API call ended in.

A case may end in a clean one-line error (exit 2 on the command line as one
line ``PROG: error: ...``; an ``InputError`` of one line through the Python
API), a falsy result with its reason (exit 1) or a valid result. Anything
else is a bug: exit 3 (an internal error), a traceback, an error of more
than one line, any other exception through the API (even a one-line
``ValueError``), a crash; or a run past the bound (out of time, out of the
address-space limit).
"""

from __future__ import annotations

#: Outcomes; the first three are what a case may end in.
ERROR, VALID, FALSY, BUG, OVER = "clean error", "valid", "falsy", "bug", "over bound"
#: What a case may end in.
ACCEPTED = (ERROR, VALID, FALSY)
#: Every outcome, in the campaign table's order.
OUTCOMES = (ERROR, VALID, FALSY, BUG, OVER)


def classify_cli(prog: str, code, out: str, err: str) -> tuple[str, str]:
    """The outcome of a command line from its exit code and output: exit 2 is
    a clean error only as one line ``PROG: error: ...``; exit 3 (an internal
    error) and any traceback are bugs."""
    if "Traceback" in err:
        return BUG, err[-2000:]
    if code == 0:
        return VALID, ""
    if code == 1 and prog == "matcher":
        # localize prints 'not localised: REASON'; track one line a frame, with its reason
        said = out.strip().splitlines()
        reason = next((ln for ln in said if ln.startswith("not localised")), said[-1] if said else "")
        return (FALSY, reason) if reason else (BUG, f"exit 1 without a reason: {err[-500:]}")
    if code == 2:
        errors = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith(f"{prog}: warning:")]
        if len(errors) == 1 and errors[0].startswith(f"{prog}: error: out of memory"):
            return OVER, errors[0]  # the --mem-gb limit
        if len(errors) == 1 and errors[0].startswith(f"{prog}: error: "):
            return ERROR, errors[0]
        return BUG, f"exit 2 but not one error line: {err[-1000:]}"
    return BUG, f"exit {code}: {err[-1000:]}"


def classify_input_error(message: str) -> tuple[str, str]:
    """An ``InputError`` through the API: a clean error only if its message
    is one line."""
    return (ERROR, message) if message and "\n" not in message else (BUG, f"InputError not one line: {message!r}")
