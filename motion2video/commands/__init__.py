"""The sub-commands of ``motion2video``: one module per command (``render.py`` for ``motion2video render``), each
parsing its arguments into a settings dataclass and calling one function below it. Their one-line summaries, in
the order ``motion2video --help`` lists them, are :data:`motion2video.cli.SUMMARIES`."""
