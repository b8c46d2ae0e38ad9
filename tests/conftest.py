"""Shows the bpy 5.2 run (tests/test_blender_on_bpy52.py) in the terminal summary: its count and
skip reasons, which -q and -rs would otherwise hide inside that one test."""


def pytest_terminal_summary(terminalreporter):
    lines = [line
             for outcome in ("passed", "failed")
             for report in terminalreporter.stats.get(outcome, [])
             if report.when == "call"
             for name, value in report.user_properties if name == "bpy 5.2"
             for line in value]
    if lines:
        terminalreporter.section("tests/blender under bpy 5.2 (.venv313)")
        for line in lines:
            terminalreporter.write_line(line)
