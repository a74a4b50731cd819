"""The rcsa REST service (FastAPI): ``service.main.create_app`` builds it; ``rcsa serve`` runs it."""
