"""What a person looks at: live lines, reports, plots, animations, the Foxglove view.

Everything here reads runs (a trace, or the events of one running) and draws or prints
them; nothing here changes a run. Plots need the optional extra ``mdle[plot]``.
"""
