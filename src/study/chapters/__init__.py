"""The book's chapters, one module per page, named after it: each ``compute(runner)`` runs its page's
experiments (every run cached) and returns the page's typed result. No chapter module imports another."""
