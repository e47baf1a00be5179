"""Issue 14's reference runs and their exact comparison (``results/refactor_issue14/``)."""
