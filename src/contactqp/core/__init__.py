"""The core: reduced model, contacts, friction law, local (FCLIB) forms, problems, results and
certificates, load histories.

Nothing here imports a method, a file format, a study or an application.
"""
