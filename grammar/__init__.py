"""The MDLe grammar, shipped inside the installed package as ``mdle.grammar``.

``mdle.lark`` in this folder is the only definition of MDLe's syntax. ``mdle/grammar``
is a link to this folder, so the file ships inside the ``mdle`` package and the parser
finds it with :func:`importlib.resources.files` in any install (wheel or editable).
"""
