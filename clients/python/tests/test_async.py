"""The asynchronous client: the same answers as the synchronous one."""

from __future__ import annotations

import asyncio

import pytest

from test_client import PLAN, SPEC
from vigil_client import AsyncVigil, Vigil, VigilError


def test_async_plans_sessions_and_errors(vigil_url: str) -> None:
    async def run() -> None:
        async with AsyncVigil(vigil_url) as vigil:
            assert (await vigil.health()).status == "ok"
            plans = await asyncio.gather(*(vigil.plan("paper-v10", PLAN) for _ in range(4)))
            assert len({p.expected_detections for p in plans}) == 1
            with Vigil(vigil_url) as sync:
                assert plans[0].expected_detections == sync.plan("paper-v10", PLAN).expected_detections
            inline = await vigil.plan_inline({"scenario": SPEC, "sensors": [{"id": "s", "x": 95, "y": 45}]})
            created = await vigil.create_scenario(SPEC)
            assert (await vigil.get_scenario(created.id)).id == inline.scenario == created.id
            assert (await vigil.stats(created.id)).cols == 20
            async with await vigil.session(created.id) as session:
                step = await session.step({"sensors": [{"id": "s", "x": 95, "y": 45}]})
                assert step.step == 0
                assert (await session.refresh()).step == 1
            with pytest.raises(VigilError) as gone:
                await session.refresh()
            assert gone.value.status == 404
            await vigil.delete_scenario(created.id)
            with pytest.raises(VigilError) as missing:
                await vigil.delete_scenario(created.id)
            assert missing.value.status == 404

    asyncio.run(run())
